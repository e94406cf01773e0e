"""`prepare_priors`: the clip reconstruction reads, with each prior from the chosen source."""

from __future__ import annotations

import inspect
from dataclasses import replace
from typing import Any

from ..language.vocabulary import SETTING_LAYOUTS
from ..scene import GeneratedClip
from .masks import plan_targets, static_plan_labels
from .protocol import PriorEstimators
from .rgb import RGBPriorEstimators
from .sizes import planned_sizes

__all__ = ["PRIOR_NAMES", "PRIOR_SOURCES", "CLOSED_SETTINGS", "GROUNDLESS_SETTINGS", "default_estimators", "prepare_priors", "setting_label",
           "open_sky", "setting_word"]

PRIOR_NAMES = ("depth", "masks", "tracks")
PRIOR_SOURCES = ("auto", "estimated", "ground_truth")
#: Settings closed by walls: what a frame shows above the horizon is a backdrop near the scene.
CLOSED_SETTINGS = tuple(n for n, layout in SETTING_LAYOUTS.items() if layout.walls)
#: Settings up in the air: no ground near enough to see as one; everything but the objects is sky.
GROUNDLESS_SETTINGS = tuple(n for n, layout in SETTING_LAYOUTS.items() if not layout.ground)


def _carried(clip: GeneratedClip, name: str = "") -> str:
    """What prior `name` of a clip is: what its info says (e.g. "corrupted"), else the
    generator's renders of its ground truth ("ground_truth") or what the clip says it carries."""
    said = clip.info.get("priors")
    if isinstance(said, dict) and said.get(name):
        return str(said[name])
    if clip.ground_truth is not None:
        return "ground_truth"
    return str(said) if said and not isinstance(said, dict) else "clip"


def setting_label(clip: GeneratedClip) -> str:
    """The setting's object name: the plan's setting word in its canonical form, named as the
    generator names that background ("underwater" -> "water", "room" -> "floor"), "ground"
    without one."""
    name = setting_word(clip)
    if name is None:
        return "ground"
    layout = SETTING_LAYOUTS.get(name)
    return layout.label if layout is not None else name


def setting_word(clip: GeneratedClip) -> str | None:
    """The plan's setting in its canonical form ("field" -> "grass"), None without one."""
    from ..language.vocabulary import word_to_setting

    s = clip.info.get("setting")
    return (word_to_setting(str(s).lower()) or str(s)) if s else None


def open_sky(clip: GeneratedClip) -> bool:
    """Whether what the clip shows above the ground's horizon is sky (far beyond the scene: left
    empty, so the reconstruction makes it the scene's sky) rather than a backdrop (part of the
    setting): sky unless the plan names a setting closed by walls (`CLOSED_SETTINGS`)."""
    return setting_word(clip) not in CLOSED_SETTINGS


def _accepted(method: Any, kwargs: dict[str, Any]) -> dict[str, Any]:
    """The keyword arguments of `kwargs` that `method` takes (all of them with a **kwargs)."""
    try:
        params = inspect.signature(method).parameters
    except (TypeError, ValueError):
        return {}
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return dict(kwargs)
    return {k: v for k, v in kwargs.items() if k in params}


#: Under an open sky, a planned clip's ground is taken to end this many camera heights away
#: (`RGBPriorEstimators.far_heights`; the farther rows are a backdrop there, such as hedges or hills).
FAR_HEIGHTS = 8.0


def default_estimators(clip: GeneratedClip, **overrides: Any) -> RGBPriorEstimators:
    """The `RGBPriorEstimators` `prepare_priors` uses for `clip` (its setting's label, a backdrop
    unless the sky is open, no ground for a scene up in the sky), with `overrides` of its fields.
    Under an open sky the ground reaches `FAR_HEIGHTS` camera heights (a fixed 50 m made the
    bus's far road, camera 8.1 m up, a wall at 48.6 m: novel views 3-5 dB worse). Not where
    walls close the view (`CLOSED_SETTINGS`): the floor and a wall at 8 heights stood in two
    pieces where the room's wall is, and a room's novel views lost 3-11 dB (the held-out cat,
    its first run); there the floor still reaches `max_depth`, and a wall stands where the
    setting's colour changes above it (`walls`)."""
    sky = open_sky(clip)
    est = RGBPriorEstimators(setting_label=setting_label(clip), backdrop=not sky, walls=not sky,
                             ground=setting_word(clip) not in GROUNDLESS_SETTINGS,
                             far_heights=FAR_HEIGHTS if sky else None)
    return replace(est, **overrides) if overrides else est


def prepare_priors(clip: GeneratedClip, source: str = "auto", estimators: PriorEstimators | None = None) -> GeneratedClip:
    """A copy of `clip` whose depth, masks and tracks come from `source`:

    - "auto": the priors the clip carries; the missing ones estimated from the frames;
    - "estimated": all three estimated from the frames (what the clip carries is ignored);
    - "ground_truth": the clip's own priors as they are (a `ValueError` names the missing ones).

    `info["priors"]` of the copy maps each prior to where it came from ("estimated", or what the
    clip carried: "ground_truth" for the generator's renders). Masks are estimated before depth
    (object depth comes from where the masks meet the ground)."""
    if source not in PRIOR_SOURCES:
        raise ValueError(f"Expected priors source in {PRIOR_SOURCES}, found {source!r}")
    have = {n: getattr(clip, n) is not None for n in PRIOR_NAMES}
    if source == "ground_truth":
        missing = [n for n in PRIOR_NAMES if not have[n]]
        if missing:
            raise ValueError(f"Expected a clip carrying depth, masks and tracks for priors='ground_truth', "
                             f"missing {missing}")
        return replace(clip, info={**clip.info, "priors": {n: _carried(clip, n) for n in PRIOR_NAMES}})
    estimate = {n: source == "estimated" or not have[n] for n in PRIOR_NAMES}
    if not any(estimate.values()):
        return replace(clip, info={**clip.info, "priors": {n: _carried(clip, n) for n in PRIOR_NAMES}})
    est = estimators if estimators is not None else default_estimators(clip)
    fields: dict[str, Any] = {}
    masks, labels = clip.masks, dict(clip.labels)
    if estimate["masks"]:
        targets = plan_targets(clip.info, clip.num_frames, clip.width, clip.height)
        extra = _accepted(est.masks, {"static_labels": static_plan_labels(clip.info)})
        out = est.masks(clip.frames, None, targets, cameras=clip.cameras, **extra)
        masks, labels = (None, {}) if out is None else out
        fields.update(masks=masks, labels=labels)
    if estimate["depth"]:
        extra = {"labels": labels, "sizes": planned_sizes(clip.info)}
        accepted = _accepted(est.depth, extra)          # estimators without size priors still work
        fields["depth"] = est.depth(clip.frames, clip.cameras, masks=masks, **accepted)
    if estimate["tracks"]:
        out = est.tracks(clip.frames)
        fields["tracks"], fields["track_visible"] = (None, None) if out is None else out
    origin = {n: ("estimated" if estimate[n] else _carried(clip, n)) for n in PRIOR_NAMES}
    walls = bool(estimate["depth"] and getattr(est, "stands_walls", False))
    fields["info"] = {**clip.info, "priors": origin, "prior_estimator": type(est).__name__, "prior_walls": walls}
    return replace(clip, **fields)

