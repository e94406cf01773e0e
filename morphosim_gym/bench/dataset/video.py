"""Camera streams as mp4 files (PyAV): many episodes per file, one after another, frame k of a file
at time k / fps; what `info.json` says about a video feature.

LeRobot's default encoder is SVT-AV1 (`libsvtav1`, yuv420p, a keyframe every 2 frames, crf 30);
`h264` (libx264) and `hevc` work too. B-frames are off, so frame timestamps are exactly
k / fps and an episode's frames are `[from_timestamp, to_timestamp)` of its file.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

import numpy as np

from .layout import VIDEO_FILE_MB, DatasetLayout, FileCursor

__all__ = ["VideoSettings", "VideoFileWriter", "video_info", "read_frames", "VCODECS"]

VCODECS = ("libsvtav1", "h264", "hevc")


def _av() -> Any:
    try:
        import av
    except ImportError:
        raise ValueError("Expected the av (PyAV) package to write videos, found it missing; "
                         "pip install -e '.[data]'") from None
    return av


@dataclass(frozen=True)
class VideoSettings:
    """How camera streams are encoded (recorded in `info.json` as `video.*`).

    Attributes:
        vcodec: "libsvtav1" (AV1, LeRobot's default), "h264" or "hevc".
        pix_fmt: pixel format (yuv420p needs even image sizes).
        g: keyframe interval, frames (small = fast random access).
        crf: quality (lower = better, larger files).
        preset: encoder speed preset (None = the codec's default; 12 for SVT-AV1 as LeRobot).
    """

    vcodec: str = "libsvtav1"
    pix_fmt: str = "yuv420p"
    g: int = 2
    crf: int = 30
    preset: Optional[int] = None

    def __post_init__(self) -> None:
        if self.vcodec not in VCODECS:
            raise ValueError(f"Expected vcodec in {VCODECS}, found {self.vcodec!r}")
        if self.g < 1 or self.crf < 0:
            raise ValueError(f"Expected g >= 1 and crf >= 0, found g={self.g}, crf={self.crf}")

    def options(self) -> dict[str, str]:
        """The encoder options (strings, as PyAV wants them)."""
        opts = {"g": str(self.g), "crf": str(self.crf)}
        if self.vcodec == "libsvtav1":
            opts["preset"] = str(12 if self.preset is None else self.preset)
            opts["svtav1-params"] = "lp=1"              # one thread: the same bytes on every machine
        else:
            opts.update(bf="0", threads="1")
            if self.vcodec == "hevc":
                opts["x265-params"] = "log-level=error"
            if self.preset is not None:
                opts["preset"] = str(self.preset)
        return opts

    def available(self) -> None:
        """Raise a clear error when PyAV here has no encoder for `vcodec`."""
        av = _av()
        try:
            av.codec.Codec(self.vcodec, "w")
        except Exception:
            raise ValueError(f"Expected PyAV to have a {self.vcodec!r} encoder, found none; choose another "
                             f"--vcodec among {VCODECS}") from None

    def info(self) -> dict[str, Any]:
        """The encoder fields LeRobot records beside what it reads from the stream."""
        return {"video.g": self.g, "video.crf": self.crf,
                "video.preset": 12 if self.preset is None and self.vcodec == "libsvtav1" else self.preset,
                "video.fast_decode": 0, "video.video_backend": "pyav", "video.extra_options": {}}


class VideoFileWriter:
    """Appends episodes of one camera to `videos/{key}/chunk-XXX/file-XXX.mp4`, starting a new file
    when the current one passes `max_mb` (encoded bytes).

    Args:
        layout: the dataset's paths.
        key: the video feature ("observation.images.main").
        fps: frames per second (an integer).
        settings: the encoder.
        max_mb: file size limit, megabytes.
    """

    def __init__(self, layout: DatasetLayout, key: str, fps: int, settings: VideoSettings,
                 max_mb: float = VIDEO_FILE_MB, chunks_size: int = 1000) -> None:
        self.layout, self.key, self.fps, self.settings, self.max_mb = layout, key, fps, settings, max_mb
        self.cursor = FileCursor(chunks_size)
        self._container: Any = None
        self._stream: Any = None
        self._path: Optional[Path] = None
        self._frames = 0                     # frames already in the current file
        self._bytes = 0                      # encoded bytes in the current file

    def append(self, frames: np.ndarray) -> dict[str, Any]:
        """Encode frames [T, H, W, 3] uint8 as the next episode; returns its `videos/{key}/...` columns."""
        if frames.ndim != 4 or frames.shape[-1] != 3 or frames.dtype != np.uint8:
            raise ValueError(f"Expected frames [T, H, W, 3] uint8, found {frames.shape} {frames.dtype}")
        if self._container is not None and self._bytes >= self.max_mb * 1024 ** 2:
            self.close()
            self.cursor.advance()
        if self._container is None:
            self._open(frames.shape[2], frames.shape[1])
        av = _av()
        start = self._frames
        for img in frames:
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(img), format="rgb24")
            frame.pts = self._frames
            self._frames += 1
            self._mux(self._stream.encode(frame))
        p = f"videos/{self.key}"
        return {f"{p}/chunk_index": self.cursor.chunk_index, f"{p}/file_index": self.cursor.file_index,
                f"{p}/from_timestamp": start / self.fps, f"{p}/to_timestamp": self._frames / self.fps}

    def _mux(self, packets: Any) -> None:
        for packet in packets:
            self._bytes += packet.size
            self._container.mux(packet)

    def _open(self, width: int, height: int) -> None:
        if self.settings.pix_fmt == "yuv420p" and (width % 2 or height % 2):
            raise ValueError(f"Expected even image sizes for pix_fmt yuv420p, found {width}x{height}")
        av = _av()
        os.environ.setdefault("SVT_LOG", "1")          # SVT-AV1 prints errors only (not its banner per file)
        self._path = self.layout.video(self.key, self.cursor.chunk_index, self.cursor.file_index)
        self._path.parent.mkdir(parents=True, exist_ok=True)
        self._container = av.open(str(self._path), "w")
        self._stream = self._container.add_stream(self.settings.vcodec, self.fps, options=self.settings.options())
        self._stream.pix_fmt = self.settings.pix_fmt
        self._stream.width, self._stream.height = width, height
        self._frames = self._bytes = 0

    def close(self) -> None:
        """Flush the encoder and close the current file."""
        if self._container is None:
            return
        self._mux(self._stream.encode())
        self._container.close()
        self._container = self._stream = None


def video_info(path: Path, settings: VideoSettings) -> dict[str, Any]:
    """A video feature's `info` as LeRobot writes it: what the stream says, then the encoder fields."""
    av = _av()
    with av.open(str(path)) as c:
        s = c.streams.video[0]
        info: dict[str, Any] = {"video.height": s.height, "video.width": s.width, "video.codec": s.codec.canonical_name,
                                "video.pix_fmt": s.pix_fmt, "video.fps": int(s.base_rate), "video.channels": 3,
                                "has_audio": bool(c.streams.audio)}
    for k, v in settings.info().items():
        info.setdefault(k, v)
    info["is_depth_map"] = False
    return info


def read_frames(path: Path, from_timestamp: float, to_timestamp: float) -> tuple[np.ndarray, np.ndarray]:
    """Decode the frames of `path` with timestamps in [from, to): (frames [T, H, W, 3] uint8, times [T])."""
    av = _av()
    frames, times = [], []
    with av.open(str(path)) as c:
        s = c.streams.video[0]
        for f in c.decode(s):
            t = float(f.pts * s.time_base)
            if t >= to_timestamp - 1e-6:
                break
            if t >= from_timestamp - 1e-6:
                frames.append(f.to_ndarray(format="rgb24"))
                times.append(t)
    return (np.stack(frames) if frames else np.zeros((0, 0, 0, 3), np.uint8)), np.array(times)
