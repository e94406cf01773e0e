"""Named reconstruction settings: "full" (the method as published here) and "fast" (tests, envs on
tiny clips, quick looks), and `resolve_reconstruction_config` that turns a name into its config.

    SimConfig(reconstruction="fit", reconstruction_config="fast")

"fast" runs about an eighth of the full schedule (150 fit steps instead of 1200, 40 polish steps,
60 feature steps, no densification) without progress bars; its scenes are blurrier and their feature fields
coarser, but edits still select through the feature field. A preset is a starting point: pass a
`ReconstructionConfig` (e.g. `dataclasses.replace(RECONSTRUCTION_PRESETS["fast"], seed=1)`) for
anything else.
"""

from __future__ import annotations

from typing import Any

from .features import FeatureConfig
from .fit import FitConfig
from .pipeline import ReconstructionConfig

__all__ = ["RECONSTRUCTION_PRESETS", "resolve_reconstruction_config"]

RECONSTRUCTION_PRESETS: dict[str, ReconstructionConfig] = {
    "full": ReconstructionConfig(),
    "fast": ReconstructionConfig(fit=FitConfig(iterations=150, progress=False),     # ends before densification
                                 features=FeatureConfig(iterations=60, progress=False), complete_iterations=40,
                                 progress=False),
}
"""Preset name -> its `ReconstructionConfig`."""


def resolve_reconstruction_config(spec: Any) -> ReconstructionConfig:
    """The `ReconstructionConfig` of `spec`: itself, a preset's by name, or "full" for None;
    `ValueError` listing the presets for anything else."""
    if spec is None:
        return RECONSTRUCTION_PRESETS["full"]
    if isinstance(spec, ReconstructionConfig):
        return spec
    if isinstance(spec, str) and spec in RECONSTRUCTION_PRESETS:
        return RECONSTRUCTION_PRESETS[spec]
    raise ValueError(f"Expected reconstruction_config as a ReconstructionConfig or a preset name in "
                     f"{sorted(RECONSTRUCTION_PRESETS)}, found {spec!r}")
