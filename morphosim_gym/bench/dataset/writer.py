"""Write a LeRobot v3.0 dataset from episodes staged on disk (see `layout` for the files).

`write_dataset` rebuilds every file of the dataset from the staged episodes, in the order given
(episode_index = position). `meta/info.json` goes last and is removed first: a folder with an
info.json holds a complete dataset, one without it a dataset being (re)written.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

import numpy as np

from ..store import atomic_write_bytes
from .features import ACTION, STATE, FrameSchema
from .layout import (CHUNKS_SIZE, CODEBASE_VERSION, DATA_FILE_MB, DATA_PATH, VIDEO_FILE_MB, VIDEO_PATH,
                     DatasetLayout, FileCursor)
from .staging import load_staged
from .stats import feature_stats, image_stats, merge_stats, to_json
from .video import VideoFileWriter, VideoSettings, video_info

__all__ = ["EpisodeInput", "write_dataset"]


def _pa() -> Any:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise ValueError("Expected the pyarrow package to write datasets, found it missing; "
                         "pip install -e '.[data]'") from None
    return pa, pq


@dataclass(frozen=True)
class EpisodeInput:
    """One episode to write: its staged steps and extra per-episode columns (name -> value)."""

    staged: Path
    extra: dict[str, Any] = field(default_factory=dict)


class _ParquetFiles:
    """Appends tables (one row group each) to the files `path_of(chunk, file)`, starting a new file past
    `max_mb` (uncompressed bytes, as LeRobot counts)."""

    def __init__(self, path_of: Callable[[int, int], Path], max_mb: float, chunks_size: int) -> None:
        self._path_of, self.max_mb = path_of, max_mb
        self.cursor = FileCursor(chunks_size)
        self._writer: Any = None
        self._bytes = 0

    def append(self, table: Any) -> tuple[int, int]:
        """Write `table`; returns the (chunk, file) index it went to."""
        _, pq = _pa()
        if self._writer is not None and self._bytes + table.nbytes > self.max_mb * 1024 ** 2:
            self.close()
            self.cursor.advance()
        if self._writer is None:
            path = self._path_of(self.cursor.chunk_index, self.cursor.file_index)
            path.parent.mkdir(parents=True, exist_ok=True)
            self._writer = pq.ParquetWriter(str(path), table.schema, compression="snappy")
            self._bytes = 0
        self._writer.write_table(table)
        self._bytes += table.nbytes
        return self.cursor.chunk_index, self.cursor.file_index

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None


def _frame_table(schema: FrameSchema, steps: Any, episode_index: int, first_index: int, fps: int,
                 task_index: np.ndarray) -> Any:
    pa, _ = _pa()
    t = len(steps)

    def vectors(x: np.ndarray, d: int) -> Any:
        return pa.FixedSizeListArray.from_arrays(pa.array(np.asarray(x, np.float32).reshape(-1)), d)

    done = steps.terminated | steps.truncated
    cols = {STATE: vectors(steps.observations["proprio"], schema.state_dim),
            ACTION: vectors(steps.actions, schema.action_dim),
            "next.reward": pa.array(steps.rewards.astype(np.float32)), "next.done": pa.array(done),
            "next.truncated": pa.array(steps.truncated), "next.success": pa.array(steps.success),
            "timestamp": pa.array((np.arange(t) / fps).astype(np.float32)),
            "frame_index": pa.array(np.arange(t, dtype=np.int64)),
            "episode_index": pa.array(np.full(t, episode_index, np.int64)),
            "index": pa.array(np.arange(first_index, first_index + t, dtype=np.int64)),
            "task_index": pa.array(task_index.astype(np.int64))}
    return pa.table(cols)


def _episode_stats(schema: FrameSchema, steps: Any, table: Any) -> dict[str, dict[str, np.ndarray]]:
    out = {key: image_stats(steps.observations[obs_key]) for (obs_key, _), key in zip(schema.cameras,
                                                                                       schema.video_keys)}
    for name in table.column_names:
        col = table.column(name).combine_chunks()
        values = np.asarray(col.flatten()).reshape(len(col), -1) if name in (STATE, ACTION) else \
            np.asarray(col.to_numpy(zero_copy_only=False))
        out[name] = feature_stats(values)
    return out


def _column(pa: Any, values: list) -> Any:
    arr = pa.array(values)
    if pa.types.is_null(arr.type):
        return pa.array(values, pa.string())
    if pa.types.is_list(arr.type) and pa.types.is_null(arr.type.value_type):
        return pa.array(values, pa.list_(pa.string()))
    return arr


def _write_episodes(layout: DatasetLayout, rows: list[dict], max_mb: float, chunks_size: int) -> None:
    pa, pq = _pa()
    cursor, start, size = FileCursor(chunks_size), 0, 0
    groups: list[tuple[int, int, int, int]] = []          # (chunk, file, first row, end row)
    for i, row in enumerate(rows):
        n = len(json.dumps(row, default=str))
        if i > start and size + n > max_mb * 1024 ** 2:
            groups.append((cursor.chunk_index, cursor.file_index, start, i))
            cursor.advance()
            start, size = i, 0
        size += n
        row["meta/episodes/chunk_index"], row["meta/episodes/file_index"] = cursor.chunk_index, cursor.file_index
    groups.append((cursor.chunk_index, cursor.file_index, start, len(rows)))
    for chunk, file, a, b in groups:
        part = rows[a:b]
        if not part:
            continue
        table = pa.table({k: _column(pa, [r[k] for r in part]) for k in part[0]})
        path = layout.episodes(chunk, file)
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(table, str(path), compression="snappy")


def _write_tasks(layout: DatasetLayout, tasks: dict[str, int]) -> None:
    """`meta/tasks.parquet` as pandas writes a frame indexed by "task" with a `task_index` column
    (LeRobot reads it with `pandas.read_parquet`, which restores the index from this metadata)."""
    pa, pq = _pa()
    names = sorted(tasks, key=tasks.get)
    table = pa.table({"task_index": pa.array([tasks[n] for n in names], pa.int64()), "task": pa.array(names,
                                                                                                       pa.string())})
    meta = {"index_columns": ["task"], "column_indexes": [{"name": None, "field_name": None, "pandas_type": "unicode",
                                                           "numpy_type": "object", "metadata": {"encoding": "UTF-8"}}],
            "columns": [{"name": "task_index", "field_name": "task_index", "pandas_type": "int64",
                         "numpy_type": "int64", "metadata": None},
                        {"name": "task", "field_name": "task", "pandas_type": "unicode", "numpy_type": "object",
                         "metadata": None}],
            "creator": {"library": "pyarrow", "version": pa.__version__}, "pandas_version": "2.2.3"}
    table = table.replace_schema_metadata({b"pandas": json.dumps(meta).encode()})
    layout.tasks.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(table, str(layout.tasks))


def _json(path: Path, data: Any) -> None:
    atomic_write_bytes(path, (json.dumps(data, indent=4) + "\n").encode())


def _clear(layout: DatasetLayout) -> None:
    layout.info.unlink(missing_ok=True)                   # first: the folder no longer claims a dataset
    for p in layout.outputs:
        if p.is_dir():
            shutil.rmtree(p)


class _Episodes:
    """Writes episodes one after another into the data and video files; keeps their rows, stats, tasks."""

    def __init__(self, layout: DatasetLayout, schema: FrameSchema, fps: int, video: VideoSettings,
                 data_file_mb: float, video_file_mb: float, chunks_size: int) -> None:
        self.schema, self.fps = schema, fps
        self.data = _ParquetFiles(layout.data, data_file_mb, chunks_size)
        self.videos = {key: VideoFileWriter(layout, key, fps, video, video_file_mb, chunks_size)
                       for key in schema.video_keys}
        self.tasks: dict[str, int] = {}
        self.rows: list[dict] = []
        self.stats: list[dict] = []
        self.frames = 0

    def add(self, ep: EpisodeInput) -> None:
        schema, ep_index = self.schema, len(self.rows)
        steps = load_staged(ep.staged)
        schema.check(steps.observations, steps.actions, str(ep.staged))
        for text in steps.instructions:
            self.tasks.setdefault(text, len(self.tasks))
        task_index = np.array([self.tasks[s] for s in steps.instructions], np.int64)
        table = _frame_table(schema, steps, ep_index, self.frames, self.fps, task_index)
        chunk, file = self.data.append(table)
        row: dict[str, Any] = {"episode_index": ep_index, "tasks": list(dict.fromkeys(steps.instructions)),
                               "length": len(steps), "data/chunk_index": chunk, "data/file_index": file,
                               "dataset_from_index": self.frames, "dataset_to_index": self.frames + len(steps)}
        for (obs_key, _), key in zip(schema.cameras, schema.video_keys):
            row.update(self.videos[key].append(steps.observations[obs_key]))
        stats = _episode_stats(schema, steps, table)
        for feat, st in stats.items():
            row.update({f"stats/{feat}/{k}": np.asarray(v).tolist() for k, v in st.items()})
        row.update(ep.extra)
        self.rows.append(row)
        self.stats.append(stats)
        self.frames += len(steps)

    def close(self) -> None:
        self.data.close()
        for w in self.videos.values():
            w.close()

    def merged_stats(self) -> dict:
        return {k: merge_stats([s[k] for s in self.stats]) for k in (self.stats[0] if self.stats else {})}


def write_dataset(root: str | Path, schema: FrameSchema, fps: int, episodes: Sequence[EpisodeInput],
                  video: VideoSettings = VideoSettings(), robot_type: Optional[str] = None,
                  data_file_mb: float = DATA_FILE_MB, video_file_mb: float = VIDEO_FILE_MB,
                  chunks_size: int = CHUNKS_SIZE) -> dict:
    """Write the dataset of `episodes` under `root`, replacing any dataset files there; returns the
    `info.json` dict. Episode i of `episodes` is episode_index i."""
    if isinstance(fps, bool) or not isinstance(fps, int) or fps < 1:
        raise ValueError(f"Expected fps as a positive integer, found {fps!r}")
    video.available()
    layout = DatasetLayout(Path(root))
    _clear(layout)
    eps = _Episodes(layout, schema, fps, video, data_file_mb, video_file_mb, chunks_size)
    try:
        for ep in episodes:
            eps.add(ep)
    finally:
        eps.close()
    if eps.rows:
        _write_episodes(layout, eps.rows, data_file_mb, chunks_size)
    _write_tasks(layout, eps.tasks)
    _json(layout.stats, to_json(eps.merged_stats()))
    infos = {key: video_info(layout.video(key, 0, 0), video) for key in schema.video_keys} if eps.rows else {}
    n = len(eps.rows)
    info = {"codebase_version": CODEBASE_VERSION, "robot_type": robot_type, "total_episodes": n,
            "total_frames": eps.frames, "total_tasks": len(eps.tasks), "chunks_size": chunks_size,
            "data_files_size_in_mb": data_file_mb, "video_files_size_in_mb": video_file_mb, "fps": fps,
            "splits": {"train": f"0:{n}"}, "data_path": DATA_PATH, "video_path": VIDEO_PATH,
            "features": schema.features(infos)}
    _json(layout.info, info)                               # last: the dataset is complete
    return info
