"""Priors from RGB alone: depth, instance masks and point tracks estimated from a clip's frames.

A layer of its own below generate and reconstruct (it imports only `scene`): any clip source
(the procedural generator, the diffusion backend, a video file) and reconstruction share one
`PriorEstimators` protocol. `RGBPriorEstimators` is the offline default (CPU, no weights);
`prepare_priors` fills a clip's missing (or all) priors and records in `clip.info["priors"]`
which were estimated.
"""

from .confidence import mask_confidence, prior_confidences, track_confidence
from .corrupt import corrupt_priors
from .depth import contact_depth, ground_plane_depth
from .masks import motion_foreground, plan_targets
from .prepare import PRIOR_SOURCES, default_estimators, prepare_priors, setting_label
from .protocol import BoxTrack, PlanTarget, PriorEstimators
from .rgb import RGBPriorEstimators
from .sizes import CATEGORY_SIZES, ObjectSize, planned_sizes, size_depth
from .tracks import flow_tracks

__all__ = ["mask_confidence", "prior_confidences", "track_confidence", "CATEGORY_SIZES", "ObjectSize", "planned_sizes", "size_depth", "PRIOR_SOURCES", "BoxTrack", "PlanTarget", "PriorEstimators", "RGBPriorEstimators", "contact_depth",
           "corrupt_priors", "default_estimators", "flow_tracks", "ground_plane_depth", "motion_foreground", "plan_targets",
           "prepare_priors", "setting_label"]
