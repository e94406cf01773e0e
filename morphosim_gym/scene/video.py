"""Frames from a video file (mp4, avi, mov, mkv, webm, gif) or a folder of images, read to a budget.

`read_frames(path, max_frames, size)` decodes a clip and brings it within the budget: frames
are resized so the longer side is at most `size` pixels (never enlarged); an edited video is cut
into its shots and one is kept (the longest by default); when the shot has more than
`max_frames` frames every k-th frame is kept (k the smallest stride that fits, so the whole shot
is covered at a lower frame rate, but never below `min_fps`: then the first `max_frames` frames
at that rate are kept). What was done is in `VideoFrames.info`. Files that
cannot be decoded, folders without images, images of different sizes, and clips with fewer than
`MIN_FRAMES` frames raise a `ValueError` naming the file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

import numpy as np

__all__ = ["IMAGE_SUFFIXES", "MIN_FRAMES", "VIDEO_SUFFIXES", "VideoFrames", "read_frames"]

VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm", ".m4v", ".gif")
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")
MIN_FRAMES = 3          # fewer frames show no motion worth fitting (and leave no frame to hold out)
MIN_SIDE = 16           # pixels of the shorter side after resizing
FOLDER_FPS = 10.0       # a folder of images has no frame rate of its own
MAX_DECODED = 3000      # frames read (at the budget size) before the rest of a file is ignored


@dataclass(frozen=True)
class VideoFrames:
    """A decoded clip within the budget.

    Attributes:
        frames: [T, H, W, 3] uint8 RGB.
        fps: frames per second of `frames` (the source's divided by the stride).
        info: source path, source frame count, size and fps, stride, whether resized / subsampled.
    """

    frames: np.ndarray
    fps: float
    info: dict[str, Any] = field(default_factory=dict)


def _rgb(image: np.ndarray, where: str) -> np.ndarray:
    """An image as [H, W, 3] uint8 (grey repeated, alpha dropped, 16-bit scaled)."""
    a = np.asarray(image)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=-1)
    if a.ndim != 3 or a.shape[-1] not in (1, 3, 4):
        raise ValueError(f"Expected RGB images, found shape {a.shape} in {where}")
    if a.shape[-1] == 1:
        a = np.repeat(a, 3, axis=-1)
    a = a[..., :3]
    if a.dtype == np.uint16:
        a = (a // 257).astype(np.uint8)
    elif a.dtype != np.uint8:
        a = np.clip(np.asarray(a, np.float64) * (255.0 if a.max() <= 1.0 else 1.0), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(a)


def _target_size(width: int, height: int, size: int) -> tuple[int, int]:
    """(w, h) with the longer side at most `size` (aspect kept, even sizes, never enlarged)."""
    scale = min(1.0, size / max(width, height))
    w, h = max(2, int(round(width * scale / 2)) * 2), max(2, int(round(height * scale / 2)) * 2)
    return (width, height) if scale >= 1.0 else (w, h)


def _resize(image: np.ndarray, wh: tuple[int, int]) -> np.ndarray:
    import cv2

    if (image.shape[1], image.shape[0]) == wh:
        return image
    return cv2.resize(image, wh, interpolation=cv2.INTER_AREA)


def _folder_images(path: Path) -> list[Path]:
    files = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise ValueError(f"Expected image files ({', '.join(IMAGE_SUFFIXES)}) in the folder {path}, found none")
    return files


def _iter_folder(files: list[Path]) -> Iterator[np.ndarray]:
    import imageio.v3 as iio

    first: tuple[int, ...] | None = None
    for f in files:
        try:
            img = _rgb(iio.imread(f), str(f))
        except (OSError, ValueError, RuntimeError) as exc:
            raise ValueError(f"Expected a readable image, found {f} could not be decoded ({exc})") from exc
        if first is None:
            first = img.shape
        elif img.shape != first:
            raise ValueError(f"Expected frames of one size in {f.parent}, found {f.name} at "
                             f"{img.shape[1]}x{img.shape[0]} while {files[0].name} is {first[1]}x{first[0]}")
        yield img


def _plugin(path: Path) -> str | None:
    return None if path.suffix.lower() == ".gif" else "pyav"


def _file_fps(path: Path) -> float | None:
    """The file's frame rate from its metadata (None where it does not say)."""
    import imageio.v3 as iio

    try:
        meta = iio.immeta(path, plugin=_plugin(path))
    except Exception as exc:  # noqa: BLE001 - every decoder failure becomes one clear message
        raise ValueError(f"Expected a decodable video, found {path} could not be opened ({exc})") from exc
    if meta.get("fps"):
        return float(meta["fps"])
    if meta.get("duration"):                     # gif: milliseconds per frame
        return 1000.0 / float(meta["duration"])
    return None


def _iter_file(path: Path) -> Iterator[np.ndarray]:
    import imageio.v3 as iio

    try:
        for frame in iio.imiter(path, plugin=_plugin(path)):
            yield _rgb(frame, str(path))
    except Exception as exc:  # noqa: BLE001 - every decoder failure becomes one clear message
        if isinstance(exc, ValueError) and str(path) in str(exc):
            raise
        raise ValueError(f"Expected a decodable video, found {path} could not be decoded ({exc})") from exc


def _check_budget(max_frames: int, size: int) -> None:
    if isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer)) or max_frames < MIN_FRAMES:
        raise ValueError(f"Expected max_frames as an integer >= {MIN_FRAMES}, found {max_frames!r}")
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or not MIN_SIDE <= size <= 4096:
        raise ValueError(f"Expected size (the longer side in pixels) as an integer in [{MIN_SIDE}, 4096], "
                         f"found {size!r}")


def read_frames(path: str | Path, max_frames: int = 49, size: int = 160, fps: float | None = None,
                shot: int | str = "longest", min_fps: float = 5.0, start: int = 0) -> VideoFrames:
    """Decode `path` (a video file or a folder of images, sorted by name) within the budget.

    Args:
        path: an mp4/avi/mov/mkv/webm/gif file, or a folder of png/jpg/... frames of one size.
        max_frames: keep at most this many frames (every k-th when the shot is longer).
        size: the longer side of the frames in pixels (frames are shrunk, never enlarged).
        fps: the source frame rate; None: the file's own (`FOLDER_FPS` for a folder).
        shot: an edited video is split at its cuts (`shots.split_shots`) and one shot is kept:
            "longest", or its index.
        min_fps: the kept frames are never sparser than this (motion between frames stays small
            enough to track): a shot longer than `max_frames` at that rate is cut to its first
            `max_frames` frames (info["window"] says which).
        start: source frames of the kept shot skipped before the window begins (0: from the shot's start).

    Returns:
        `VideoFrames` with frames [T, H, W, 3] uint8, T in [MIN_FRAMES, max_frames]; its info says
        which shot was kept, the stride, and whether frames were resized or the read truncated
        (at `MAX_DECODED` frames).
    """
    from .shots import choose_shot, split_shots

    _check_budget(max_frames, size)
    if isinstance(start, bool) or not isinstance(start, (int, np.integer)) or start < 0:
        raise ValueError(f"Expected start as an integer >= 0 (source frames to skip), found {start!r}")
    p = Path(path)
    if not p.exists():
        raise ValueError(f"Expected a video file or a folder of frames, found no such path: {p}")
    for name, value in (("fps", fps), ("min_fps", min_fps)):
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"Expected {name} > 0, found {value!r}")
    if p.is_dir():
        source_fps, frames_in = FOLDER_FPS, _iter_folder(_folder_images(p))
    else:
        if p.suffix.lower() not in VIDEO_SUFFIXES:
            raise ValueError(f"Expected a video file ({', '.join(VIDEO_SUFFIXES)}) or a folder of frames, "
                             f"found {p}")
        source_fps, frames_in = _file_fps(p), _iter_file(p)
    source_fps = float(fps) if fps is not None else (source_fps or FOLDER_FPS)
    decoded, wh, source_wh = [], None, None
    for i, frame in enumerate(frames_in):
        if source_wh is None:
            source_wh = (frame.shape[1], frame.shape[0])
            wh = _target_size(*source_wh, size)
            if min(wh) < MIN_SIDE:
                raise ValueError(f"Expected frames at least {MIN_SIDE} px on the shorter side after resizing, "
                                 f"found {source_wh[0]}x{source_wh[1]} -> {wh[0]}x{wh[1]} in {p}")
        elif (frame.shape[1], frame.shape[0]) != source_wh:
            raise ValueError(f"Expected frames of one size in {p}, found frame {i} at {frame.shape[1]}x"
                             f"{frame.shape[0]} after {source_wh[0]}x{source_wh[1]}")
        decoded.append(_resize(frame, wh))
        if len(decoded) >= MAX_DECODED:
            break
    seen = len(decoded)
    if seen < MIN_FRAMES:
        what = "no decodable frame" if seen == 0 else "a single frame" if seen == 1 else f"{seen} frames"
        raise ValueError(f"Expected a clip of at least {MIN_FRAMES} frames, found {what} in {p}")
    all_frames = np.stack(decoded)
    shots = split_shots(all_frames)
    shot_start, stop = choose_shot(shots, shot)
    start = shot_start + int(start)
    if stop - start < MIN_FRAMES:
        raise ValueError(f"Expected a shot of at least {MIN_FRAMES} frames after start, found shot "
                         f"{shots.index((shot_start, stop))} of {p} with {stop - start} (frames {start}-{stop - 1})")
    stride = max(1, min(math.ceil((stop - start) / max_frames), int(source_fps // min_fps)))
    window = (start, min(stop, start + stride * (max_frames - 1) + 1))
    kept = all_frames[window[0]:window[1]:stride]
    info = {"source": str(p), "source_frames": seen, "source_size": list(source_wh), "source_fps": source_fps,
            "shots": [list(s) for s in shots], "shot": [shot_start, stop], "window": list(window),
            "stride": stride, "size": [wh[0], wh[1]],
            "resized": wh != source_wh, "subsampled": stride > 1, "truncated": seen >= MAX_DECODED}
    return VideoFrames(np.ascontiguousarray(kept), source_fps / stride, info)
