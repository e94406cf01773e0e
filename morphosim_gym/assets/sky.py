"""Sky panoramas: an HDR equirectangular image -> a tone-mapped sky and colours for camera rays.

Equirectangular convention (Blender's, z-up world): the image's centre column looks along +x,
u grows as the azimuth turns from +x towards -y, row 0 is straight up, the last row straight down.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..scene.camera import Camera
from .errors import AssetError
from .texture import sample_texture

__all__ = ["Sky", "directions_to_uv", "load_sky", "read_exr", "tone_map"]


def read_exr(path: str | os.PathLike) -> np.ndarray:
    """Linear RGB float32 [H, W, 3] of an OpenEXR file (`AssetError` naming the file if unreadable)."""
    try:
        import OpenEXR
    except ImportError:
        raise AssetError(f"Reading {path} needs the OpenEXR package: pip install OpenEXR") from None
    try:
        with OpenEXR.File(str(path)) as f:
            channels = f.channels()
            if "RGB" in channels:
                rgb = channels["RGB"].pixels
            elif "RGBA" in channels:
                rgb = channels["RGBA"].pixels[..., :3]
            else:
                rgb = np.stack([channels[c].pixels for c in "RGB"], axis=-1)
    except AssetError:
        raise
    except Exception as exc:  # noqa: BLE001 - OpenEXR raises RuntimeError, KeyError, ...
        raise AssetError(f"Cannot read the panorama {path} ({type(exc).__name__}: {exc})") from None
    rgb = np.asarray(rgb, dtype=np.float32)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.size == 0:
        raise AssetError(f"Expected an RGB image in {path}, found an array of shape {rgb.shape}")
    return np.nan_to_num(rgb, nan=0.0, posinf=0.0, neginf=0.0).clip(0, None)


def tone_map(hdr: np.ndarray, exposure: float = 1.0, gamma: float = 2.2) -> np.ndarray:
    """Linear HDR -> display RGB float32 in [0, 1] (Reinhard x / (1 + x), then gamma)."""
    x = np.asarray(hdr, dtype=np.float32) * np.float32(exposure)
    return np.clip(x / (1.0 + x), 0.0, 1.0) ** np.float32(1.0 / gamma)


def directions_to_uv(directions: np.ndarray) -> np.ndarray:
    """Equirectangular (u, v) in [0, 1] of world directions (z-up); v = 1 straight up. [N, 3] -> [N, 2]"""
    d = np.asarray(directions, dtype=np.float64)
    if d.ndim != 2 or d.shape[1] != 3:
        raise ValueError(f"Expected directions of shape (N, 3), found {d.shape}")
    n = np.linalg.norm(d, axis=1, keepdims=True)
    d = d / np.where(n > 0, n, 1.0)
    u = 0.5 - np.arctan2(d[:, 1], d[:, 0]) / (2 * np.pi)
    v = 0.5 + np.arcsin(np.clip(d[:, 2], -1, 1)) / np.pi
    return np.stack([u, v], axis=1)


@dataclass
class Sky:
    """A tone-mapped equirectangular sky.

    Attributes:
        image: display RGB in [0, 1], row 0 straight up. [H, W, 3] float32
        name: where it came from.
    """

    image: np.ndarray
    name: str = ""

    def sky_color(self, directions: np.ndarray) -> np.ndarray:
        """The sky's colour seen along each ray (z-up world), bilinear. [N, 3] -> float32 [N, 3]"""
        uv = directions_to_uv(directions)
        h = self.image.shape[0]
        uv[:, 1] = np.clip(uv[:, 1], 0.5 / h, 1 - 0.5 / h)   # no wrap over the poles
        return sample_texture(self.image, uv)

    def background(self, camera: Camera) -> np.ndarray:
        """The sky behind every pixel of `camera`: float32 [H, W, 3]. Composite a render over it
        with `rgb + (1 - alpha[..., None]) * sky.background(camera)` (render on a black background)."""
        points = camera.unproject(camera.pixel_centres(), np.ones((camera.height, camera.width)))
        rays = (points - camera.position).reshape(-1, 3)
        return self.sky_color(rays).reshape(camera.height, camera.width, 3)


def load_sky(path: str | os.PathLike, exposure: float = 1.0) -> Sky:
    """A `Sky` from an HDR panorama (`.exr`)."""
    return Sky(tone_map(read_exr(path), exposure), name=Path(path).stem)
