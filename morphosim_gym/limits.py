"""Size limits on what a user may ask for, from memory estimates, so a typo ("4096" frames, a 16384²
render, `--episodes 100000000`) is a clear `ValueError` stating the estimate instead of a machine
that swaps until it is killed.

The limits are generous for real use:

- a generated clip (frames uint8 RGB + float32 depth + int32 instance masks, 11 bytes a pixel a
  frame) fits in `MAX_CLIP_BYTES` (4 GiB: 49 frames at 2048², or 1000 frames at 512²);
- a render is at most `MAX_RENDER_SIDE` (4096) pixels a side and its outputs (float32 rgb, depth,
  alpha, instance and any feature channels, for every camera) fit in `MAX_RENDER_BYTES` (4 GiB);
- a benchmark suite has at most `MAX_EPISODES` (10^6) seeds.
"""

from __future__ import annotations

__all__ = [
    "CLIP_BYTES_PER_PIXEL",
    "EPISODE_PLAN_BYTES",
    "MAX_CLIP_BYTES",
    "MAX_EPISODES",
    "MAX_RENDER_BYTES",
    "MAX_RENDER_SIDE",
    "check_clip_size",
    "check_render_size",
    "clip_bytes",
    "format_bytes",
]

MAX_CLIP_BYTES = 4 << 30
MAX_RENDER_SIDE = 4096
MAX_RENDER_BYTES = 4 << 30
MAX_EPISODES = 1_000_000
CLIP_BYTES_PER_PIXEL = {"frames": 3, "depth": 4, "masks": 4}
RENDER_CHANNELS = 6                # rgb 3, depth, alpha, instance; float32 each, plus feature channels
EPISODE_PLAN_BYTES = 300           # bookkeeping per planned episode of a sweep (measured: ~290 bytes)


def format_bytes(n: float) -> str:
    """`~47 GiB`, `~512 MiB`, `~3 KiB`."""
    for unit, size in (("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if n >= size:
            return f"~{n / size:.3g} {unit}"
    return f"{int(n)} bytes"


def clip_bytes(num_frames: int, width: int, height: int) -> dict[str, int]:
    """Bytes of each array of a generated clip of this size."""
    return {k: num_frames * width * height * b for k, b in CLIP_BYTES_PER_PIXEL.items()}


def check_clip_size(num_frames: int, width: int, height: int) -> None:
    """`ValueError` stating the estimate if a clip of this size would not fit in `MAX_CLIP_BYTES`."""
    parts = clip_bytes(num_frames, width, height)
    total = sum(parts.values())
    if total > MAX_CLIP_BYTES:
        detail = ", ".join(f"{k} {format_bytes(v)}" for k, v in parts.items())
        raise ValueError(f"Expected a clip that fits in memory: {num_frames} frames of {width}x{height} would need "
                         f"{format_bytes(total)} ({detail}); the limit is {format_bytes(MAX_CLIP_BYTES)} "
                         f"(morphosim_gym.limits.MAX_CLIP_BYTES); use fewer frames or smaller frames")


def check_render_size(cameras: int, width: int, height: int, feature_dim: int = 0) -> None:
    """`ValueError` for a render larger than `MAX_RENDER_SIDE` a side or `MAX_RENDER_BYTES` of outputs."""
    if max(width, height) > MAX_RENDER_SIDE:
        raise ValueError(f"Expected a render of at most {MAX_RENDER_SIDE} pixels a side, found {width}x{height} "
                         f"(its outputs alone would need "
                         f"{format_bytes(cameras * width * height * (RENDER_CHANNELS + feature_dim) * 4)})")
    total = cameras * width * height * (RENDER_CHANNELS + feature_dim) * 4
    if total > MAX_RENDER_BYTES:
        raise ValueError(f"Expected a render that fits in memory: {cameras} cameras of {width}x{height} with "
                         f"{feature_dim} feature channels would need {format_bytes(total)}; the limit is "
                         f"{format_bytes(MAX_RENDER_BYTES)} (morphosim_gym.limits.MAX_RENDER_BYTES); render fewer "
                         f"cameras at a time")
