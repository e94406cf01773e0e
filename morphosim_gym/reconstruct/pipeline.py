"""`reconstruct(clip)`: a monocular clip to a dynamic Gaussian `Scene4D` with a feature field.

Steps (MoSca / Feature 4X style, sized for a 2-core CPU):
    1. initialise from the depth prior and instance masks; separate static and dynamic
       instances with the tracks; a scaffold of rigid nodes per dynamic instance (`initialize.py`);
    2. fit Gaussians and node poses to every frame with the differentiable renderer: L1 + SSIM,
       depth, masks, tracks, ARAP and smooth-motion terms, densify and prune (`fit.py`);
    3. complete what the monocular view never saw (`completion.py`);
    4. distil the feature field with the geometry frozen (`features.py`).
Priors come from `config.priors` (`morphosim_gym.priors.prepare_priors`): by default ("auto")
the ones the clip carries, with the missing ones estimated from the frames (a clip of frames
and cameras alone is reconstructed, never refused); "estimated" estimates all three;
"ground_truth" takes the clip's own as they are. A clip in which nothing can be seen to move
(a single frame, or frames that do not change) has estimated masks holding only the setting and
is reconstructed as that static setting (a reduced result, not an error). Where the estimated
priors stand a room's walls near (`info["prior_walls"]`), the fit keeps Gaussians within
`NEAR_WALL_FOOTPRINTS` of their first size, the completion continues the wall in the colours the
views show, and the background is the farthest pixels' colour. Only the clip's frames, cameras and priors
are used, never `clip.ground_truth`. Results are
cached on disk by the content hash of the clip and the configuration (atomic writes), so a
second call with the same clip and settings loads the scene instead of fitting again.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..priors import PRIOR_SOURCES, prepare_priors
from ..scene import GeneratedClip, Provenance, Scene4D, SceneObject, load_scene, save_scene
from ..scene.diskcache import load_or_build
from .features import FeatureConfig, distill_features
from .fit import FitConfig, fit
from .initialize import InitConfig, initialize
from .labels import with_prompt_objects
from .lifting import estimate_background_color
from .sky import sky_from_clip
from .video_labels import video_estimators

__all__ = ["ReconstructionConfig", "reconstruct", "validate_clip", "cache_key", "cache_path"]

CACHE_VERSION = 37     # bumped when the method changes, so older results are fitted again
#: Where the estimated priors stand a room's walls at their distance (`RGBPriorEstimators.walls`),
#: the fit keeps each Gaussian within this many times its first size (`Strategy.max_footprints`):
#: a still camera cannot tell a floor-coloured streak along the wall's foot from the table's edge,
#: and a turned view shows it across the wall.
NEAR_WALL_FOOTPRINTS = 16.0


@dataclass(frozen=True)
class ReconstructionConfig:
    """All reconstruction settings (each part has its own dataclass).

    Attributes:
        init, fit, features: the settings of each stage.
        priors: where depth, masks and tracks come from: "auto" (the clip's, missing ones
            estimated), "estimated" (all from the frames) or "ground_truth" (the clip's as is).
        complete: add Gaussians for what the input view never saw (ground beyond the view,
            the far side of objects).
        complete_iterations: fit iterations after completion (blend the added ground in).
        sky: give the scene a sky image made from the pixels the priors leave empty (no depth,
            no instance: `reconstruct.sky`), fitted behind the Gaussians; False: those pixels
            show the background colour.
        seed: random seed (same clip, config and seed: the same scene).
        cache: load / store results in `cache_dir` (default `$MORPHOSIM_CACHE/reconstruct`).
        cache_dir: cache location, or None for the default.
        progress: tqdm bars.
    """

    init: InitConfig = field(default_factory=InitConfig)
    fit: FitConfig = field(default_factory=FitConfig)
    features: FeatureConfig = field(default_factory=FeatureConfig)
    priors: str = "auto"
    complete: bool = True
    complete_iterations: int = 200
    sky: bool = True
    seed: int = 0
    cache: bool = True
    cache_dir: str | None = None
    progress: bool = True

    def __post_init__(self) -> None:
        if self.priors not in PRIOR_SOURCES:
            raise ValueError(f"Expected priors in {PRIOR_SOURCES}, found {self.priors!r}")


def validate_clip(clip: Any) -> None:
    """Raise `ValueError` naming the problem if a clip cannot be reconstructed (before any work)."""
    if not isinstance(clip, GeneratedClip):
        raise ValueError(f"Expected a GeneratedClip, found {type(clip).__name__}")
    missing = [n for n in ("depth", "masks") if getattr(clip, n) is None]
    if missing:
        raise ValueError(f"Expected a clip with depth and instance-mask priors for reconstruction, "
                         f"missing {missing} (the prior estimator returned none)")
    if not np.any(clip.depth > 0):
        raise ValueError("Expected a depth prior with some positive depths, found none")
    if not np.any(clip.masks >= 0):
        raise ValueError("Expected instance masks covering some pixels, found only background")


def cache_key(clip: GeneratedClip, config: ReconstructionConfig) -> str:
    """Content hash of what the result depends on (the clip's inputs, never its ground truth)."""
    cfg = asdict(config)
    for k in ("cache", "cache_dir", "progress"):
        cfg.pop(k)
    for part in ("fit", "features"):
        cfg[part].pop("progress", None)
    h = hashlib.sha256()
    h.update(clip.content_hash().encode())
    h.update(json.dumps(cfg, sort_keys=True, default=str).encode())
    h.update(f"v{CACHE_VERSION}".encode())
    estimators = video_estimators(clip)        # a video's labels come from its prompt
    if estimators is not None:
        h.update(repr(estimators).encode())
    return h.hexdigest()[:32]


def cache_path(clip: GeneratedClip, config: ReconstructionConfig) -> Path:
    """Where `reconstruct(clip, config)` stores its result (whether or not caching is on)."""
    root = Path(config.cache_dir) if config.cache_dir else Path(
        os.environ.get("MORPHOSIM_CACHE", Path.home() / ".cache" / "morphosim_gym")) / "reconstruct"
    return root / f"{cache_key(clip, config)}.msim"


def _objects(clip: GeneratedClip, ids: list[int]) -> list[SceneObject]:
    from ..language.vocabulary import noun_to_category, word_to_setting

    out = []
    for i in ids:
        label = clip.labels.get(i, f"object {i}")
        setting = word_to_setting(label.lower())
        hit = noun_to_category(label.lower())
        category = hit[0] if hit else (setting or label)
        out.append(SceneObject(i, label, category, role="background" if setting and not hit else "object",
                               dynamic=False))
    return out


def reconstruct(clip: GeneratedClip, config: ReconstructionConfig | None = None) -> Scene4D:
    """Fit a `Scene4D` to a clip (see the module docstring). `ValueError` before any work if the
    clip (or its estimated priors) cannot be reconstructed."""
    cfg = config or ReconstructionConfig()
    if not isinstance(clip, GeneratedClip):
        raise ValueError(f"Expected a GeneratedClip, found {type(clip).__name__}")
    if cfg.cache:
        scene = load_or_build(cache_path(clip, cfg), load_scene, lambda: _fit_scene(clip, cfg), save_scene)
    else:
        scene = _fit_scene(clip, cfg)
    return with_prompt_objects(scene, clip)          # the prompt's categories and colours (after the cache)


def _fit_scene(clip: GeneratedClip, cfg: ReconstructionConfig) -> Scene4D:
    start = time.perf_counter()
    source = clip
    clip = prepare_priors(source, cfg.priors, estimators=video_estimators(source))
    validate_clip(clip)
    fit_cfg = cfg.fit if cfg.progress else _no_progress(cfg.fit)
    feat_cfg = cfg.features if cfg.progress else _no_progress(cfg.features)
    near_walls = bool(clip.info.get("prior_walls"))
    if near_walls and fit_cfg.strategy.max_footprints is None:
        fit_cfg = replace(fit_cfg, strategy=replace(fit_cfg.strategy, max_footprints=NEAR_WALL_FOOTPRINTS))
    init = initialize(clip, cfg.init, seed=cfg.seed)
    model = init.model
    background = estimate_background_color(clip, far_share=0.05 if near_walls else None)
    sky = sky_from_clip(clip) if cfg.sky else None
    fit_log = fit(model, clip, init.reference, init.dynamic, fit_cfg, seed=cfg.seed, background=background, sky=sky)
    if cfg.complete:
        from .completion import complete

        t_complete = time.perf_counter()
        fit_log["completion"] = complete(model, clip, init.dynamic, seed=cfg.seed, reference=init.reference,
                                         seen_colours=near_walls)
        fit_log["completion"]["seconds"] = time.perf_counter() - t_complete
        if cfg.complete_iterations > 0:
            # no densification in this short pass: only blend in what completion added
            polish = replace(fit_cfg, iterations=cfg.complete_iterations,
                             strategy=replace(fit_cfg.strategy, refine_start=cfg.complete_iterations + 1))
            fit_log["complete"] = fit(model, clip, init.reference, init.dynamic, polish, seed=cfg.seed + 1,
                                      background=background, sky=sky)
    decoders, feat_log = distill_features(model, clip, feat_cfg, seed=cfg.seed)
    gaussians, motion = model.to_scene_parts()
    ids = sorted(int(i) for i in np.unique(clip.masks) if i >= 0)
    objects = _objects(clip, ids)
    objects = [SceneObject(o.id, o.name, o.category, None, bool(init.dynamic.get(o.id, False)), o.role) for o in objects]
    present = set(np.unique(gaussians.object_ids).tolist())
    objects = [o for o in objects if o.id in present]
    seconds = time.perf_counter() - start
    scene = Scene4D(gaussians, motion, objects, clip.fps, clip.cameras if len({c.world_to_camera.tobytes()
                                                                                 for c in clip.cameras}) > 1 else
                    (clip.cameras[0],), decoders=decoders,
                    provenance=Provenance(clip.prompt or None, clip.info.get("seed"), clip.info.get("backend", "clip"),
                                          f"fit:{cache_key(source, cfg)}"),
                    background=background, sky=sky)
    scene._fit_log = {"fit": fit_log, "features": feat_log, "seconds": seconds,  # for reports (not saved)
                      "priors": clip.info["priors"]}
    return scene


def _no_progress(c: Any) -> Any:
    return replace(c, progress=False)
