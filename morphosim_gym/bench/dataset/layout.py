"""Where the files of a LeRobot v3.0 dataset go, and how episodes roll over from file to file.

    meta/info.json                                  features, fps, counts, path templates
    meta/stats.json                                 per-feature stats over the whole dataset
    meta/tasks.parquet                              task (language instruction) -> task_index
    meta/episodes/chunk-000/file-000.parquet        one row per episode (many episodes per file)
    data/chunk-000/file-000.parquet                 one row per frame (many episodes per file)
    videos/{video_key}/chunk-000/file-000.mp4       one video per camera per file

A file holds episodes until it reaches its size limit; a chunk folder holds `chunks_size` files.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["CODEBASE_VERSION", "DatasetLayout", "FileCursor", "INFO_PATH", "STATS_PATH", "TASKS_PATH",
           "DATA_PATH", "VIDEO_PATH", "EPISODES_PATH", "CHUNKS_SIZE", "DATA_FILE_MB", "VIDEO_FILE_MB"]

CODEBASE_VERSION = "v3.0"
CHUNKS_SIZE = 1000                    # files per chunk folder
DATA_FILE_MB = 100                    # size limit of a data (and episodes) parquet file
VIDEO_FILE_MB = 200                   # size limit of a video file
_CHUNK_FILE = "chunk-{chunk_index:03d}/file-{file_index:03d}"
INFO_PATH = "meta/info.json"
STATS_PATH = "meta/stats.json"
TASKS_PATH = "meta/tasks.parquet"
EPISODES_PATH = "meta/episodes/" + _CHUNK_FILE + ".parquet"
DATA_PATH = "data/" + _CHUNK_FILE + ".parquet"
VIDEO_PATH = "videos/{video_key}/" + _CHUNK_FILE + ".mp4"


@dataclass
class FileCursor:
    """The (chunk, file) index of the file being written; `advance` moves to the next file."""

    chunks_size: int = CHUNKS_SIZE
    chunk_index: int = 0
    file_index: int = 0

    def advance(self) -> None:
        """The next file (the next chunk folder after `chunks_size` files)."""
        self.file_index += 1
        if self.file_index == self.chunks_size:
            self.chunk_index, self.file_index = self.chunk_index + 1, 0


@dataclass(frozen=True)
class DatasetLayout:
    """Paths of a dataset rooted at `root`."""

    root: Path

    def data(self, chunk_index: int, file_index: int) -> Path:
        return self.root / DATA_PATH.format(chunk_index=chunk_index, file_index=file_index)

    def video(self, video_key: str, chunk_index: int, file_index: int) -> Path:
        return self.root / VIDEO_PATH.format(video_key=video_key, chunk_index=chunk_index, file_index=file_index)

    def episodes(self, chunk_index: int, file_index: int) -> Path:
        return self.root / EPISODES_PATH.format(chunk_index=chunk_index, file_index=file_index)

    @property
    def info(self) -> Path:
        return self.root / INFO_PATH

    @property
    def stats(self) -> Path:
        return self.root / STATS_PATH

    @property
    def tasks(self) -> Path:
        return self.root / TASKS_PATH

    @property
    def outputs(self) -> tuple[Path, ...]:
        """The folders and files the dataset consists of (what a rewrite replaces)."""
        return (self.root / "data", self.root / "videos", self.root / "meta")
