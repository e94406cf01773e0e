"""Reconstruction: lift a monocular clip to dynamic 3D Gaussians with a motion scaffold and a feature field."""

from .pipeline import ReconstructionConfig, cache_key, reconstruct, validate_clip
from .report import format_report, quality_report

__all__ = ["ReconstructionConfig", "reconstruct", "validate_clip", "cache_key", "quality_report", "format_report"]
