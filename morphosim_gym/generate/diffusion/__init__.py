"""Diffusion clip backend: CogVideoX text-to-video with the paper's trajectory attention guidance
(the Dynamic Control Submodule). Optional: needs ``pip install "morphosim-gym[diffusion]"`` and
local weights; the procedural generator is the offline default.

Public names:
    `DiffusionClipBackend`, `DiffusionConfig`: text + trajectory boxes -> `GeneratedClip`.
    `planned.PlannedDiffusionGenerator`: the same behind the `ClipGenerator` protocol (plan, seed,
        prompt -> clip, its boxes from the trajectory planner); `SimConfig(generator="diffusion")`.
    `GuidanceTarget`: motion words + one normalised box per video frame (from the planner).
    `GuidanceConfig`, `guided_sample`: the guided denoising loop for any CogVideoX transformer.
    `PriorEstimators`, `DefaultPriorEstimators`: pluggable depth / masks / tracks.
    `TrajectoryAttnProcessor`, `AttentionStore`, `tokens_to_latent_grid`, energies: building blocks.

Importing this package does not import diffusers; constructing the backend does.
"""

from .attention import (
                        AttentionStore,
                        EarlyExit,
                        TrajectoryAttnProcessor,
                        attention_layer_names,
                        install_trajectory_processors,
                        tokens_to_latent_grid,
)
from .backend import DEFAULT_EYE, DEFAULT_FOV_Y_DEG, DEFAULT_TARGET, DiffusionClipBackend, DiffusionConfig
from .energy import frame_energy, in_box_fraction, target_attention, trajectory_loss
from .priors import DefaultPriorEstimators, PriorEstimators, flow_tracks, ground_plane_depth
from .sampler import GuidanceConfig, GuidanceTrace, cogvideox_rotary_embeddings, guided_sample
from .targets import (
                        GuidanceTarget,
                        boxes_to_latent_frames,
                        latent_frame_groups,
                        rasterize_boxes,
                        token_indices_for_words,
)

__all__ = [
    "DiffusionClipBackend", "DiffusionConfig", "DEFAULT_EYE", "DEFAULT_FOV_Y_DEG", "DEFAULT_TARGET",
    "GuidanceTarget", "GuidanceConfig", "GuidanceTrace", "guided_sample", "cogvideox_rotary_embeddings",
    "PriorEstimators", "DefaultPriorEstimators", "flow_tracks", "ground_plane_depth",
    "AttentionStore", "EarlyExit", "TrajectoryAttnProcessor", "attention_layer_names",
    "install_trajectory_processors", "tokens_to_latent_grid",
    "frame_energy", "in_box_fraction", "target_attention", "trajectory_loss",
    "boxes_to_latent_frames", "latent_frame_groups", "rasterize_boxes", "token_indices_for_words",
]
