"""Language layer: command parameterizer (text -> `Plan`), vocabularies, and text embeddings.

    >>> import morphosim_gym as ms
    >>> plan = ms.parse("a red ball bounces from right to left")
    >>> plan.mode, plan.objects[0].category, plan.motions[0].direction_world
    ('generate', 'ball', (-1.0, 0.0, 0.0))

Modules: `plan` (types, validation, JSON), `vocabulary` (categories and settings),
`lexicon` (word tables), `rules` (the offline parser, a package: tokens, nouns, motion, scanner, camera,
segments, describe, edits, targets, parser), `grounding` (nouns -> categories, targets ->
scene objects), `embeddings` (MiniLM text embeddings, shared with later layers), `llm` (optional
OpenAI-compatible backend), `evaluate` / `bench` (corpus accuracy and timing), `cli`. Colour names
live below every layer, in `morphosim_gym.colors`.
"""

from .api import parse
from .plan import (CAMERA_MOTIONS, EDIT_KINDS, EDIT_OPS, MODES, PATHS, RECOLOR_MODES, CameraOp, CameraSpec, ColorSpec,
                   EditOp, ExtractOp, MotionSpec, ObjectSpec, Plan, RecolorOp, RedirectOp, RemoveOp, ReverseOp, SpeedOp,
                   StopOp, Target, edit_op)

__all__ = ["parse", "Plan", "ObjectSpec", "MotionSpec", "CameraSpec", "ColorSpec", "EditOp", "Target", "MODES",
           "PATHS", "CAMERA_MOTIONS", "EDIT_OPS", "RECOLOR_MODES", "RecolorOp", "RemoveOp", "ExtractOp", "ReverseOp",
           "RedirectOp", "SpeedOp", "StopOp", "CameraOp", "EDIT_KINDS", "edit_op"]
