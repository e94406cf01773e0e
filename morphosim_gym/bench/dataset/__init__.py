"""Training data in the LeRobot dataset format (v3.0): features, per-frame and per-episode
parquet files, one mp4 per camera per chunk file, tasks, stats.

    from morphosim_gym.bench.dataset import write_dataset, VideoSettings

`morphosim collect` (`morphosim_gym.bench.collect`) runs the episodes and calls `write_dataset`.
The layout follows what LeRobot's own reader expects (`LeRobotDatasetMetadata`,
`LeRobotDataset`); the `lerobot` package is not needed to write or read it.
"""

from .layout import CODEBASE_VERSION, DatasetLayout
from .staging import load_staged, save_staged, staged_path
from .video import VideoSettings
from .writer import EpisodeInput, write_dataset

__all__ = ["CODEBASE_VERSION", "DatasetLayout", "VideoSettings", "EpisodeInput", "write_dataset", "save_staged",
           "load_staged", "staged_path"]
