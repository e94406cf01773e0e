"""Which Gaussians an edit target means: the paper's feature-field query with a threshold search.

1. The parser resolves the target's words to scene objects by meaning ("the vehicle" -> the
   bus; no match or an ambiguous one is an error naming the objects).
2. If the scene carries a distilled feature field (a "semantic" decoder), every Gaussian's
   latent f_j is decoded, its cosine similarities s to the prompt set T (the scene's object
   names plus the query) go through a softmax p(tau | j) = exp(s_tau / temp) / sum exp(s_i / temp),
   and the Gaussian's relevance is the probability mass of the prompts that mean the target
   (the query and the matched objects' names). When the field also has an "instance" channel
   (unit codes of the 2D masks' instances, distilled like the rest), the relevance is weighed
   by the same softmax mass over the objects' codes: names alone cannot tell "sheep 2" from
   "sheep 1" (their embeddings are 0.89 alike), the instance channel can.
3. The agent loop tries a range of thresholds on that relevance, renders each candidate
   selection from the generation camera at a few times (one pass, one channel per
   candidate), scores it (default `MaskAgreementScorer`: agreement with the 2D map of the
   target, and consistency of the selected area over time; an LLM/VLM judge can implement the
   same `CandidateScorer` interface) and keeps the best. The 2D map is evidence independent
   of the Gaussians' own object ids: the feature field queried per pixel (the rendered latents
   of the same pass, decoded and softmaxed over the prompt set like the Gaussians' relevance;
   the field was distilled from the clip's 2D masks, and rendering blends the latents of
   every Gaussian a pixel sees, so a threshold that keeps too few or too many Gaussians
   disagrees with it), or 2D masks given by the caller (`evidence`: e.g. the estimated masks
   of the input views).
Scenes without a feature field (e.g. the generator's ground truth) select the matched objects'
Gaussians by their object ids. Results are cached per scene geometry and query, so a second
edit of the same target (a recolour after a recolour, say) skips all of this.
"""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass, field
from typing import Protocol, Sequence

import numpy as np

from ..render import render
from ..scene import Scene4D, instance_codes

__all__ = ["Selection", "CandidateScorer", "MaskAgreementScorer", "Selector", "DEFAULT_THRESHOLDS", "neighbourhood_mean"]

DEFAULT_THRESHOLDS = (0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)
GROW_FLOOR = 0.05   # own relevance a Gaussian needs before its neighbourhood can raise it
TIE = 0.01          # candidate scores this close to the best count as ties


@dataclass
class Selection:
    """The Gaussians an edit applies to.

    Attributes:
        mask: [N] bool over the scene's Gaussians.
        object_ids: the scene objects the target was resolved to.
        method: "feature_field" or "object_ids".
        threshold: the chosen relevance threshold (feature field only).
        scores: (threshold, score) of every candidate tried.
        relevance: [N] relevance of each Gaussian (feature field only).
    """

    mask: np.ndarray
    object_ids: tuple[int, ...]
    method: str
    threshold: float | None = None
    scores: list[tuple[float, float]] = field(default_factory=list)
    relevance: np.ndarray | None = None


class CandidateScorer(Protocol):
    """Scores candidate selections rendered from the generation camera (higher is better)."""

    def __call__(self, soft_maps: np.ndarray, target_maps: np.ndarray) -> np.ndarray:
        """soft_maps [times, H, W, candidates], target_maps [times, H, W] bool -> [candidates] scores."""
        ...


class MaskAgreementScorer:
    """Soft IoU (sum of minima over sum of maxima) of each candidate's rendered selection with the
    target's 2D map, averaged over times, minus `consistency_weight` times the relative spread of
    the selected area over time. Soft, so that a candidate is charged for every partial
    contribution outside the target (a few Gaussians of the ground under an object) and for every
    partial miss inside it."""

    def __init__(self, consistency_weight: float = 0.2) -> None:
        self.consistency_weight = consistency_weight

    def __call__(self, soft_maps: np.ndarray, target_maps: np.ndarray) -> np.ndarray:
        soft = np.clip(soft_maps, 0.0, 1.0)                                    # [t, H, W, c]
        tgt = target_maps[..., None].astype(soft.dtype)
        inter = np.minimum(soft, tgt).sum(axis=(1, 2))
        union = np.maximum(soft, tgt).sum(axis=(1, 2))
        iou = np.where(union > 0, inter / np.maximum(union, 1e-9), 1.0).mean(axis=0)
        area = soft.sum(axis=(1, 2)).astype(np.float64)
        spread = area.std(axis=0) / np.maximum(area.mean(axis=0), 1.0)
        return iou - self.consistency_weight * spread


class Selector:
    """Turns resolved targets into Gaussian selections (see the module docstring).

    Args:
        thresholds: relevance thresholds the agent loop tries.
        temperature: softmax temperature over the prompt set.
        times: how many clip times the candidates are rendered at.
        scorer: a `CandidateScorer` (default `MaskAgreementScorer`).
        backend: renderer for the candidates.
    """

    def __init__(self, thresholds: Sequence[float] = DEFAULT_THRESHOLDS, temperature: float = 0.1, times: int = 3,
                 scorer: CandidateScorer | None = None, backend: str = "cpu") -> None:
        self.thresholds = tuple(float(t) for t in thresholds)
        self.temperature = float(temperature)
        self.times = int(times)
        self.scorer = scorer or MaskAgreementScorer()
        self.backend = backend
        self._cache: dict[tuple, Selection] = {}
        self._owners: dict[int, weakref.ref] = {}
        self._lock = threading.Lock()

    # ------------------------------------------------------------------ api
    def select(self, scene: Scene4D, object_ids: Sequence[int], query: str,
               evidence: np.ndarray | None = None) -> Selection:
        """The Gaussians of `scene` meaning `query`, which the parser resolved to `object_ids`.
        `evidence`: optional [times, H, W] bool 2D maps of the target at the selector's times
        (`np.linspace(0, duration, times)`), seen from the generation camera; by default the
        feature field's own per-pixel query."""
        ids = tuple(sorted(int(i) for i in object_ids))
        if evidence is not None:
            evidence = np.asarray(evidence, bool)
            if evidence.ndim != 3 or len(evidence) != max(1, self.times):
                raise ValueError(f"Expected evidence as [{max(1, self.times)}, H, W] bool, found {evidence.shape}")
        key = self._key(scene, ids, query) + ((None,) if evidence is None else (evidence.tobytes(),))
        with self._lock:
            hit = self._cache.get(key)
        if hit is not None:
            return hit
        has_field = "semantic" in scene.decoders and scene.gaussians.features is not None
        sel = self._feature_field(scene, ids, query, evidence) if has_field else Selection(
            np.isin(scene.gaussians.object_ids, ids), ids, "object_ids")
        with self._lock:
            self._cache[key] = sel
        return sel

    def clear(self) -> None:
        """Forget cached selections."""
        with self._lock:
            self._cache.clear()
            self._owners.clear()

    # ------------------------------------------------------------ pickling
    def __getstate__(self) -> dict:
        """The settings without the lock and the cache (keyed by array ids of this process)."""
        return {k: v for k, v in vars(self).items() if k not in ("_lock", "_cache", "_owners")}

    def __setstate__(self, state: dict) -> None:
        vars(self).update(state)
        self._cache, self._owners, self._lock = {}, {}, threading.Lock()

    # ------------------------------------------------------------ internals
    def _key(self, scene: Scene4D, ids: tuple[int, ...], query: str) -> tuple:
        """Selections depend on the geometry, ids and features, not on colours: key on the identity of
        those arrays (edits that do not touch them share them with their parent scene)."""
        g = scene.gaussians
        arrays = (g.object_ids, g.features, g.means)
        with self._lock:
            for a in arrays:
                if a is not None and id(a) not in self._owners:
                    self._owners[id(a)] = weakref.ref(a, lambda _r, k=id(a): self._drop(k))
        return tuple(id(a) for a in arrays) + (len(g), ids, query.strip().lower(), scene.num_frames)

    def _drop(self, array_id: int) -> None:
        with self._lock:
            self._owners.pop(array_id, None)
            for k in [k for k in self._cache if array_id in k[:3]]:
                del self._cache[k]

    def relevance(self, scene: Scene4D, ids: Sequence[int], query: str, features: np.ndarray | None = None
                  ) -> np.ndarray:
        """[N] relevance, per Gaussian (or per row of `features`, latents such as rendered pixels):
        the probability mass of the prompts that mean the target, times, when the field has an
        "instance" channel, the probability mass of the target objects' instance codes."""
        from ..language import embeddings

        names = [o.name for o in scene.objects]
        prompts = names + [query]
        f = scene.gaussians.features if features is None else features
        wanted = [i for i, o in enumerate(scene.objects) if o.id in set(ids)]
        mass = _softmax_mass(scene.decoders["semantic"].similarity(f, embeddings.embed(prompts)) / self.temperature,
                             wanted + [len(prompts) - 1])
        inst = scene.decoders.get("instance")
        if inst is not None:
            codes = instance_codes([o.id for o in scene.objects], inst.out_dim)
            mass = mass * _softmax_mass(inst.similarity(f, codes) / self.temperature, wanted)
        return mass

    def _feature_field(self, scene: Scene4D, ids: tuple[int, ...], query: str,
                       evidence: np.ndarray | None = None) -> Selection:
        rel = self.relevance(scene, ids, query)
        times = np.linspace(0.0, scene.duration, max(1, self.times))
        # two candidate families: the relevance itself, and the relevance raised to its spatial
        # neighbourhood's mean (a Gaussian surrounded by the target joins it: thin parts seen at
        # grazing angles, such as a roof, learn features blended with what lies behind them);
        # only Gaussians with some relevance of their own are raised, so neighbours that clearly
        # mean something else (the road under a bus) stay out
        states = [scene.at(t) for t in times]                      # skinned once, used twice
        g = states[len(states) // 2]
        near = neighbourhood_mean(g.means, rel, 3.0 * float(np.median(g.scales.max(axis=1))))
        grown = np.where(rel >= GROW_FLOOR, np.maximum(rel, near), rel)
        levels = [(t, rel) for t in self.thresholds] + [(t, grown) for t in self.thresholds]
        cands = np.stack([r >= t for t, r in levels], axis=1).astype(np.float32)         # [N, C]
        latents = np.asarray(scene.gaussians.features, np.float32)
        soft, target = [], []
        for k, (t, state) in enumerate(zip(times, states)):
            # one pass: the candidates' coverage and the rendered latents (for the 2D evidence)
            out = render(_with_features(state, np.concatenate([cands, latents], axis=1)), scene.camera_at(t),
                         backend=self.backend, features=True, background=scene.background)
            norm = out.features / np.maximum(out.alpha[..., None], 1e-6)
            soft.append(norm[..., :cands.shape[1]])
            if evidence is not None:
                target.append(evidence[k])
                continue
            pix = norm[..., cands.shape[1]:].reshape(-1, latents.shape[1])
            covered = out.alpha.reshape(-1) > 0.5
            mass = np.zeros(len(pix))
            if covered.any():
                mass[covered] = self.relevance(scene, ids, query, pix[covered])
            target.append((mass >= 0.5).reshape(out.alpha.shape))
        soft_maps = np.stack(soft)
        target_maps = np.stack(target)
        if target_maps.shape != soft_maps.shape[:3]:
            raise ValueError(f"Expected evidence of shape {soft_maps.shape[:3]}, found {target_maps.shape}")
        scores = np.asarray(self.scorer(soft_maps, target_maps), np.float64)
        # among the candidates within TIE of the best score, the most inclusive: Gaussians that
        # no rendered view shows (inside the object, behind it) cannot change the score
        near = np.flatnonzero(scores >= scores.max() - TIE)
        best = int(near[np.argmax(cands[:, near].sum(axis=0))])
        return Selection(cands[:, best] > 0.5, ids, "feature_field", levels[best][0],
                         [(t, float(s)) for (t, _), s in zip(levels, scores)], rel)


def _softmax_mass(logits: np.ndarray, wanted: Sequence[int]) -> np.ndarray:
    """[N] softmax probability of the `wanted` columns of [N, P] logits, summed."""
    s = logits - logits.max(axis=1, keepdims=True)
    p = np.exp(s)
    return p[:, list(wanted)].sum(axis=1) / p.sum(axis=1)


def neighbourhood_mean(points: np.ndarray, values: np.ndarray, voxel: float) -> np.ndarray:
    """[N] mean of `values` over the 3x3x3 voxels (of side `voxel`) around each point."""
    if len(points) == 0 or not voxel > 0:
        return values.astype(np.float64)
    keys = np.floor(points / voxel).astype(np.int64)
    keys -= keys.min(axis=0) - 1                          # >= 1, so every neighbour code is valid
    dims = keys.max(axis=0) + 2
    codes = (keys[:, 0] * dims[1] + keys[:, 1]) * dims[2] + keys[:, 2]
    uniq, inv = np.unique(codes, return_inverse=True)
    sums = np.bincount(inv, weights=values.astype(np.float64), minlength=len(uniq))
    counts = np.bincount(inv, minlength=len(uniq)).astype(np.float64)
    total, n = np.zeros(len(uniq)), np.zeros(len(uniq))
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                nb = uniq + (dx * dims[1] + dy) * dims[2] + dz
                pos = np.clip(np.searchsorted(uniq, nb), 0, len(uniq) - 1)
                hit = uniq[pos] == nb
                total[hit] += sums[pos[hit]]
                n[hit] += counts[pos[hit]]
    return (total / np.maximum(n, 1.0))[inv]


def _with_features(g, features: np.ndarray):
    from ..scene import Gaussians

    return Gaussians._trusted(means=g.means, quats=g.quats, scales=g.scales, opacities=g.opacities, colors=g.colors,
                              features=features, object_ids=g.object_ids)
