"""An instance's turns from many pairs of frames (a pose graph), not from one reference frame alone.

`lifting.instance_motion` fits each frame's rigid pose to the tracks lifted in the reference frame,
so the noise of those few reference points enters every frame's rotation, and a small object's
rotation (a ball 30 px wide, 1 px of track noise) comes out several degrees off, differently in each
frame: the fit then averages a blurred texture over inconsistent turns and does not undo them.
Here the rigid motion between many pairs of frames (gaps of 1 to 24 frames), each from the tracks
seen in both, is averaged into one rotation per frame (chordal rotation averaging, each pair
weighted by its inlier tracks, the reference frame held at the identity); the path of the
instance's centre is kept as the reference fit gave it (a centroid, which noise barely moves).

Only the clip's tracks, depth and cameras are read (never `clip.ground_truth`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import GeneratedClip
from .lifting import lift_tracks, instance_tracks, robust_kabsch

__all__ = ["PairMotion", "average_rotations", "graph_poses", "pair_motions"]

GAPS = (1, 2, 3, 4, 6, 8, 12, 16, 24)


@dataclass(frozen=True)
class PairMotion:
    """The rigid motion x_j = rotation @ x_i + translation between frames i < j, and its weight."""

    i: int
    j: int
    rotation: np.ndarray        # [3, 3]
    weight: float


def pair_motions(clip: GeneratedClip, tracks: np.ndarray, gaps: tuple[int, ...] = GAPS,
                 min_tracks: int = 6) -> list[PairMotion]:
    """Rigid motions between frames i and i + gap of the given tracks (indices into the clip's),
    each a robust Kabsch fit to those seen in both frames with a depth in both; pairs with fewer
    than `min_tracks` such tracks are left out. Weight: the fit's summed robust weights."""
    out = []
    vis = clip.track_visible[tracks]
    for i in range(clip.num_frames):
        for gap in gaps:
            j = i + gap
            if j >= clip.num_frames:
                break
            both = vis[:, i] & vis[:, j]
            if both.sum() < min_tracks:
                continue
            a, ok_a = lift_tracks(clip, i, clip.tracks[tracks[both], i])
            b, ok_b = lift_tracks(clip, j, clip.tracks[tracks[both], j])
            ok = ok_a & ok_b
            if ok.sum() < min_tracks:
                continue
            rot, _, weights = robust_kabsch(a[ok], b[ok])
            out.append(PairMotion(i, j, rot, float(weights.sum())))
    return out


def _nearest_rotation(m: np.ndarray) -> np.ndarray:
    """The rotation nearest a 3x3 matrix (Frobenius norm)."""
    u, _, vt = np.linalg.svd(m)
    return u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt


def average_rotations(rotations: np.ndarray, pairs: list[PairMotion], fixed: int, iterations: int = 50,
                      tolerance: float = 1e-7) -> np.ndarray:
    """Rotations [T, 3, 3] agreeing best with the pairs' relative rotations (R_j ~ R_ij R_i),
    starting from `rotations` and holding frame `fixed` where it is: each frame in turn becomes the
    rotation nearest the weighted sum of what its pairs say it is (block coordinate descent on the
    chordal distance), until no frame moves by more than `tolerance` (Frobenius). Frames in no pair
    keep their rotation."""
    rots = np.array(rotations, dtype=np.float64, copy=True)
    by_frame: dict[int, list[PairMotion]] = {}
    for p in pairs:
        by_frame.setdefault(p.i, []).append(p)
        by_frame.setdefault(p.j, []).append(p)
    frames = [t for t in sorted(by_frame) if t != fixed]
    for _ in range(iterations):
        moved = 0.0
        for t in frames:
            acc = np.zeros((3, 3))
            for p in by_frame[t]:
                acc += p.weight * (p.rotation @ rots[p.i] if p.j == t else p.rotation.T @ rots[p.j])
            new = _nearest_rotation(acc)
            moved = max(moved, float(np.abs(new - rots[t]).max()))
            rots[t] = new
        if moved < tolerance:
            break
    return rots


def graph_poses(clip: GeneratedClip, instance: int, reference: int, rotations: np.ndarray,
                translations: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An instance's per-frame poses (reference-frame world -> frame t, as `instance_motion`
    gives them) with their rotations averaged over the pose graph of its tracks, its `centre`
    (a reference-frame world point) kept on the same path. Unchanged without tracks or pairs."""
    if clip.tracks is None:
        return rotations, translations
    pairs = pair_motions(clip, instance_tracks(clip, instance))
    if not pairs:
        return rotations, translations
    rots = average_rotations(rotations, pairs, fixed=reference)
    path = np.einsum("tij,j->ti", rotations, centre) + translations     # where the centre goes
    return rots, path - np.einsum("tij,j->ti", rots, centre)
