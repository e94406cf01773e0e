"""An episode's steps on disk between the run and the dataset write: one compressed `.npz` per
episode under `<out>/.staging/`, written atomically (temp file + rename) before the episode's
line goes into the run's log, so every logged episode has its steps and a half-written file is
never read."""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np

from ..episode import EpisodeKey, EpisodeSteps
from ..store import atomic_write_bytes

__all__ = ["STAGING_DIR", "staged_path", "save_staged", "load_staged"]

STAGING_DIR = ".staging"
_OBS = "obs/"


def staged_path(out: Path, key: EpisodeKey) -> Path:
    """Where the steps of episode `key` are kept."""
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", key.id)
    return Path(out) / STAGING_DIR / f"{name}.npz"


def save_staged(path: Path, steps: EpisodeSteps) -> None:
    """Write `steps` to `path` atomically."""
    arrays = {_OBS + k: v for k, v in steps.observations.items()}
    arrays.update(actions=steps.actions, rewards=steps.rewards, terminated=steps.terminated,
                  truncated=steps.truncated, success=steps.success,
                  instructions=np.array(steps.instructions, dtype=np.str_))
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    atomic_write_bytes(Path(path), buf.getvalue())


def load_staged(path: Path) -> EpisodeSteps:
    """The steps written by `save_staged`."""
    with np.load(path, allow_pickle=False) as z:
        obs = {k[len(_OBS):]: z[k] for k in z.files if k.startswith(_OBS)}
        return EpisodeSteps(obs, z["actions"], z["rewards"], z["terminated"], z["truncated"], z["success"],
                            [str(s) for s in z["instructions"]])
