"""Level of detail for far objects: a documented approximation, opt-in (`render_batch(..., lod=True)`).

Each run of one object's Gaussians (contiguous, one object id, at least `MIN_RUN` long) gets,
once, a ladder of coarser sets: level k merges the Gaussians whose centres fall in one cube of
side `cell_k = base * 2**k` (base: the run's median largest scale) into one Gaussian by moment
matching (weights w = opacity x mean face area: the weighted mean, the weighted covariance of
the members' covariances plus their spread, the weighted colour and features). The coverage mass
o * 2 pi * area is kept: the members' sum, at most that of the uniform patch of the merged
variance (coverage cannot pass 1); first by the opacity (at most 0.99 and at most the union
1 - prod(1 - o)), then, once that is capped, by widening the merged Gaussian.
Per view, a run draws the coarsest level whose cell projects to at most `tol` pixels at the
run's nearest point (`cell_k * f / z_min <= tol`, z_min: camera depth of the nearest point of
its bounding sphere), else its full detail: the choice follows distance, and the merged
Gaussians are never wider than about `tol` pixels more than what they replace.

Object ids stay those of the run, so instance maps keep their labels (edges move by at most
about a cell). The ladder is built in the frame the run had when first seen and cached by the
identity of its (read-only) colour array; later frames move it by the rigid transform fitted to
`N_ANCHORS` anchor Gaussians of the run (Kabsch). Runs that do not move rigidly (anchor
residual above `RIGID_TOL` of the run's size, e.g. a skinned agent) and parts with writeable
arrays (which could change under the cache) are drawn at full detail.
"""

from __future__ import annotations

import threading
import weakref
from collections import OrderedDict
from types import SimpleNamespace
from typing import Any, Optional, Sequence

import numpy as np

__all__ = ["LOD_TOL_PX", "MIN_RUN", "ObjectLod", "build_object_lod", "merge_cells", "object_runs", "lod_parts",
           "choose_level", "clear_lod_cache", "RunLod", "BLOCK"]

LOD_TOL_PX = 1.0
"""Default largest projected cell side, in pixels, of a level drawn instead of full detail."""
MIN_RUN = 256
"""Runs of fewer Gaussians are never reduced."""
N_ANCHORS = 8
RIGID_TOL = 1e-4
_MAX_LEVELS = 8
_MIN_REDUCTION = 1.5          # a level must have at most 1 / this of the previous level's Gaussians
_CACHE_SIZE = 64


class ObjectLod:
    """The LOD ladder of one spatial block of an object run: `levels[k]` is a dict of float32
    arrays (means, quats, scales, opacities, colors, features or None) in the run's frame when it
    was built, with cell side `cells[k]`; `levels[0]` is the block at full detail (`cells[0]` 0)."""

    __slots__ = ("cells", "levels", "centre", "radius")

    def __init__(self, cells: list, levels: list, centre: np.ndarray, radius: float) -> None:
        self.cells, self.levels, self.centre, self.radius = cells, levels, centre, radius


class RunLod:
    """One object run lo:hi (object id `oid`): its spatial blocks' ladders and the anchors (local
    indices and their positions when built) that track its rigid motion."""

    __slots__ = ("lo", "hi", "oid", "blocks", "anchors", "anchor_pos", "size", "min_cell")

    def __init__(self, lo: int, hi: int, oid: int, blocks: list, anchors: np.ndarray, anchor_pos: np.ndarray,
                 size: float) -> None:
        self.lo, self.hi, self.oid, self.blocks = lo, hi, oid, blocks
        self.anchors, self.anchor_pos, self.size = anchors, anchor_pos, size
        self.min_cell = min((b.cells[1] for b in blocks if len(b.cells) > 1), default=np.inf)
        """The finest coarse cell of any block: a run nearer than min_cell * f / tol keeps full detail."""


def _rotmats(quats: np.ndarray) -> np.ndarray:
    q = quats / np.linalg.norm(quats, axis=1, keepdims=True)
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                     2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                     2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1).reshape(-1, 3, 3)


def _quats_of(R: np.ndarray) -> np.ndarray:
    """[M, 4] unit quaternions (w, x, y, z) of rotation matrices [M, 3, 3] (Shepperd's method)."""
    m = R.reshape(-1, 9)
    tr = m[:, 0] + m[:, 4] + m[:, 8]
    cand = np.stack([1 + tr, 1 + m[:, 0] - m[:, 4] - m[:, 8], 1 - m[:, 0] + m[:, 4] - m[:, 8],
                     1 - m[:, 0] - m[:, 4] + m[:, 8]], axis=1)
    k = np.argmax(cand, axis=1)
    s = np.sqrt(np.maximum(cand[np.arange(len(k)), k], 1e-30)) * 2.0
    r21, r12, r02, r20, r10, r01 = m[:, 7], m[:, 5], m[:, 2], m[:, 6], m[:, 3], m[:, 1]
    rows = {0: (s / 4, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s),
            1: ((r21 - r12) / s, s / 4, (r01 + r10) / s, (r02 + r20) / s),
            2: ((r02 - r20) / s, (r01 + r10) / s, s / 4, (r12 + r21) / s),
            3: ((r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, s / 4)}
    q = np.zeros((len(k), 4))
    for j, comps in rows.items():
        sel = k == j
        q[sel] = np.stack(comps, axis=1)[sel]
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def merge_cells(means, quats, scales, opacities, colors, features, cell: float) -> dict:
    """One LOD level: the Gaussians whose centres share a cube of side `cell`, merged by moment
    matching (see the module docstring). Returns float32 arrays means [M, 3], quats [M, 4],
    scales [M, 3], opacities [M], colors [M, 3], features [M, D] or None."""
    if not cell > 0:
        raise ValueError(f"Expected a cell side > 0, found {cell!r}")
    mu = np.asarray(means, np.float64)
    s = np.asarray(scales, np.float64)
    o = np.asarray(opacities, np.float64)
    keys = np.floor(mu / cell).astype(np.int64)
    _, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    M = int(inv.max()) + 1
    area = (s[:, 0] * s[:, 1] + s[:, 1] * s[:, 2] + s[:, 0] * s[:, 2]) / 3.0
    w = o * area + 1e-30
    wsum = np.bincount(inv, w, M)

    def wmean(x: np.ndarray) -> np.ndarray:
        return np.stack([np.bincount(inv, w * x[:, j], M) for j in range(x.shape[1])], axis=1) / wsum[:, None]

    m = wmean(mu)
    R = _rotmats(np.asarray(quats, np.float64))
    cov = np.einsum("nij,nj,nkj->nik", R, s * s, R)
    d = mu - m[inv]
    second = (cov + d[:, :, None] * d[:, None, :]).reshape(-1, 9)
    C = wmean(second).reshape(M, 3, 3)
    evals, evecs = np.linalg.eigh(C)
    evecs[np.linalg.det(evecs) < 0, :, 0] *= -1.0
    e = np.sqrt(np.maximum(evals, 1e-14))          # eigh may return tiny negatives
    m_area = (e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 0] * e[:, 2]) / 3.0
    union = 1.0 - np.exp(np.bincount(inv, np.log1p(-np.minimum(o, 0.999999)), M))
    # coverage mass o * 2 pi * area: the members' sum, at most the variance-matched uniform patch's
    # area (12 x area, coverage <= 1); kept by the opacity, then by widening once it is capped
    mass = np.minimum(2.0 * np.pi * wsum, 12.0 * m_area)
    op = np.minimum(np.minimum(mass / (2.0 * np.pi * m_area), union), 0.99)
    e = e * np.sqrt(np.maximum(mass / (2.0 * np.pi * op * m_area), 1.0))[:, None]
    f32 = np.float32
    return {"means": m.astype(f32), "quats": _quats_of(evecs).astype(f32), "scales": e.astype(f32),
            "opacities": op.astype(f32), "colors": np.clip(wmean(np.asarray(colors, np.float64)), 0, 1).astype(f32),
            "features": None if features is None else wmean(np.asarray(features, np.float64)).astype(f32)}


def object_runs(ids: np.ndarray, min_run: int = MIN_RUN) -> list[tuple[int, int]]:
    """(lo, hi) of the maximal runs of one object id (id >= 0) at least `min_run` long."""
    ids = np.asarray(ids)
    if ids.size == 0:
        return []
    cuts = np.flatnonzero(ids[1:] != ids[:-1]) + 1
    bounds = np.concatenate([[0], cuts, [ids.size]])
    return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:]) if b - a >= min_run and ids[a] >= 0]


BLOCK = 4096
"""Object runs are split into spatial blocks of at most this many Gaussians (median cuts along
the longest side), each with its own ladder: a large object (a ground plane) near the camera
keeps full detail only where it is near."""


def _blocks(mu: np.ndarray, idx: np.ndarray, block: int) -> list[np.ndarray]:
    """Index sets of at most `block` points each, by recursive median cuts along the longest side."""
    if len(idx) <= block:
        return [idx]
    pts = mu[idx]
    ax = int(np.argmax(pts.max(axis=0) - pts.min(axis=0)))
    half = len(idx) // 2
    part = np.argpartition(pts[:, ax], half)
    return _blocks(mu, idx[part[:half]], block) + _blocks(mu, idx[part[half:]], block)


def _block_lod(arrays: dict, base: float) -> ObjectLod:
    """The ladder of one block (float32 arrays of its Gaussians at full detail)."""
    mu = arrays["means"].astype(np.float64)
    cells, levels, prev = [0.0], [arrays], len(mu)
    for k in range(1, _MAX_LEVELS + 1):
        if prev <= 16:
            break
        cell = base * 2.0 ** k
        lvl = merge_cells(mu, arrays["quats"], arrays["scales"], arrays["opacities"], arrays["colors"],
                          arrays["features"], cell)
        n = len(lvl["means"])
        if n * _MIN_REDUCTION > prev:
            continue
        cells.append(cell)
        levels.append(lvl)
        prev = n
    centre = 0.5 * (mu.min(axis=0) + mu.max(axis=0))
    radius = float(np.linalg.norm(mu - centre, axis=1).max() + 3.0 * np.max(arrays["scales"]))
    return ObjectLod(cells, levels, centre, radius)


def build_object_lod(means, quats, scales, opacities, colors, features, lo: int, hi: int, oid: int,
                     block: int = BLOCK) -> RunLod:
    """The LOD ladders of Gaussians lo:hi (one object run) in their current frame."""
    sl = slice(lo, hi)
    mu = np.asarray(means[sl], np.float64)
    base = max(float(np.median(np.max(np.asarray(scales[sl], np.float64), axis=1))), 1e-6)
    blocks = []
    for idx in _blocks(mu, np.arange(hi - lo), block):
        g = idx + lo
        arrays = {k: np.ascontiguousarray(a[g], np.float32)
                  for k, a in (("means", means), ("quats", quats), ("scales", scales), ("opacities", opacities),
                               ("colors", colors))}
        arrays["features"] = None if features is None else np.ascontiguousarray(features[g], np.float32)
        blocks.append(_block_lod(arrays, base))
    centre = 0.5 * (mu.min(axis=0) + mu.max(axis=0))
    anchors = _spread_anchors(mu, centre)
    size = float(np.linalg.norm(mu.max(axis=0) - mu.min(axis=0)))
    return RunLod(lo, hi, int(oid), blocks, anchors, mu[anchors].copy(), size)


def _spread_anchors(mu: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """N_ANCHORS local indices spread over the run (extremes along the axes and diagonals)."""
    d = mu - centre
    dirs = np.array([[1, 1, 1], [-1, 1, 1], [1, -1, 1], [1, 1, -1], [-1, -1, 1], [-1, 1, -1], [1, -1, -1],
                     [-1, -1, -1]], np.float64)[:N_ANCHORS]
    return np.argmax(d @ dirs.T, axis=0).astype(np.int64)


def _fit_rigid(canon: np.ndarray, now: np.ndarray, size: float) -> Optional[tuple[np.ndarray, np.ndarray]]:
    """(R, t) with now ~ canon @ R.T + t (Kabsch), or None when the anchors did not move rigidly."""
    if np.array_equal(canon, now):
        return np.eye(3), np.zeros(3)
    ca, cb = canon.mean(axis=0), now.mean(axis=0)
    U, _, Vt = np.linalg.svd((canon - ca).T @ (now - cb))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    t = cb - R @ ca
    if np.abs(canon @ R.T + t - now).max() > RIGID_TOL * max(size, 1e-6):
        return None
    return R, t


def choose_level(obj: ObjectLod, R: np.ndarray, t: np.ndarray, viewmat, K, near: float, tol: float) -> int:
    """The coarsest level of `obj` whose cell projects to at most `tol` pixels at its nearest
    point in this view (0: full detail)."""
    c = R @ obj.centre + t
    vm = np.asarray(viewmat, np.float64)
    z = float(vm[2, :3] @ c + vm[2, 3]) - obj.radius
    if z <= max(near, 1e-6):
        return 0
    f = float(max(K[0][0], K[1][1]))
    level = 0
    for k in range(1, len(obj.cells)):
        if obj.cells[k] * f / z <= tol:
            level = k
    return level


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    aw, ax, ay, az = a
    bw, bx, by, bz = b[:, 0], b[:, 1], b[:, 2], b[:, 3]
    return np.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], axis=1)


# ------------------------------------------------------------------------------------ cache
_CACHE: "OrderedDict[tuple, tuple]" = OrderedDict()
_LOCK = threading.Lock()


def clear_lod_cache() -> None:
    """Forget every cached LOD ladder."""
    with _LOCK:
        _CACHE.clear()


def _cacheable(part: Any) -> bool:
    arrs = [part.colors, part.scales, part.opacities, getattr(part, "object_ids", None)]
    return all(isinstance(a, np.ndarray) and not a.flags.writeable for a in arrs)


def _ladders(part: Any) -> list[RunLod]:
    key = (id(part.colors), id(part.scales), id(part.object_ids), len(part.colors))
    with _LOCK:
        hit = _CACHE.get(key)
        if hit is not None and hit[0]() is part.colors:
            _CACHE.move_to_end(key)
            return hit[1]
    feats = getattr(part, "features", None)
    ladders = [build_object_lod(part.means, part.quats, part.scales, part.opacities, part.colors, feats, lo, hi,
                                part.object_ids[lo])
               for lo, hi in object_runs(part.object_ids)]
    with _LOCK:
        _CACHE[key] = (weakref.ref(part.colors), ladders)
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    return ladders


def _slice(part: Any, lo: int, hi: int) -> SimpleNamespace:
    f = getattr(part, "features", None)
    return SimpleNamespace(means=part.means[lo:hi], quats=part.quats[lo:hi], scales=part.scales[lo:hi],
                           opacities=part.opacities[lo:hi], colors=part.colors[lo:hi],
                           object_ids=part.object_ids[lo:hi], features=None if f is None else f[lo:hi])


def _placed(oid: int, obj: ObjectLod, level: int, R: np.ndarray, t: np.ndarray) -> SimpleNamespace:
    lvl = obj.levels[level]
    ids = np.full(len(lvl["means"]), oid, np.int32)
    if np.array_equal(R, np.eye(3)) and not t.any():
        return SimpleNamespace(object_ids=ids, **lvl)
    qR = _quats_of(R[None])[0]
    moved = dict(lvl, means=(lvl["means"] @ R.T.astype(np.float32) + t.astype(np.float32)).astype(np.float32),
                 quats=_quat_mul(qR, lvl["quats"].astype(np.float64)).astype(np.float32))
    return SimpleNamespace(object_ids=ids, **moved)


def lod_parts(parts: Sequence[Any], viewmat, K, near: float, tol: float = LOD_TOL_PX) -> list:
    """The parts of one view with far blocks of object runs replaced by their coarser levels: the
    given parts (or slices of them, no copies) for what stays exact, the placed levels and blocks
    for the runs that have a far block, in the parts' order. Parts that cannot be cached
    (writeable or non-numpy arrays, no object ids) and runs that did not move rigidly stay as
    they are."""
    if not tol > 0:
        raise ValueError(f"Expected an LOD tolerance > 0 pixels, found {tol!r}")
    out: list = []
    for part in parts:
        pieces = None
        if getattr(part, "object_ids", None) is not None and _cacheable(part):
            pieces = _part_pieces(part, _ladders(part), viewmat, K, near, tol)
        out.extend(pieces or [part])
    return out


def _part_pieces(part: Any, ladders: list[RunLod], viewmat, K, near: float, tol: float) -> Optional[list]:
    """One part's pieces for this view, or None when every run keeps full detail."""
    if not ladders:
        return None
    idx = np.concatenate([o.lo + o.anchors for o in ladders])
    now = np.asarray(part.means[idx], np.float64).reshape(len(ladders), N_ANCHORS, 3)
    vm = np.asarray(viewmat, np.float64)
    far = (now @ vm[2, :3] + vm[2, 3]).max(axis=1) + [o.size for o in ladders]   # >= any point's depth
    reach = np.array([o.min_cell for o in ladders]) * float(max(K[0][0], K[1][1])) / tol
    pos = 0
    pieces: list = []
    for k in np.flatnonzero(far >= reach):       # the others are too near for any coarse level
        run = ladders[k]
        fit = _fit_rigid(run.anchor_pos, now[k], run.size)
        if fit is None:
            continue
        levels = [choose_level(b, fit[0], fit[1], viewmat, K, near, tol) for b in run.blocks]
        if not any(levels):
            continue
        if run.lo > pos:
            pieces.append(_slice(part, pos, run.lo))
        pieces.extend(_placed(run.oid, b, lv, *fit) for b, lv in zip(run.blocks, levels))
        pos = run.hi
    if not pieces:
        return None
    if pos < len(part.colors):
        pieces.append(_slice(part, pos, len(part.colors)))
    return pieces
