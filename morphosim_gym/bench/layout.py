"""Where a sweep's files go inside its output folder."""

from __future__ import annotations

import re
from pathlib import Path

from .episode import EpisodeKey

__all__ = ["slug", "frames_path", "RESULTS_LOG", "MANIFEST"]

RESULTS_LOG = "results.jsonl"
MANIFEST = "manifest.json"


def slug(text: str) -> str:
    """A file-name-safe form of a policy spec ("my.mod:make" -> "my.mod_make")."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "policy"


def frames_path(out: Path, key: EpisodeKey) -> Path:
    """Where the frame strip of an episode is written."""
    return Path(out) / "frames" / slug(key.policy) / f"{key.perturbation}_{key.seed}.png"
