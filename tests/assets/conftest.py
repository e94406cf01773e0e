"""Tiny assets written by the tests: a textured, y-up OBJ (a floor quad and a plain wall)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

# 2x2 texture: top row (v near 1) red, green; bottom row (v near 0) blue, white
TEXELS = np.array([[[255, 0, 0], [0, 255, 0]], [[0, 0, 255], [255, 255, 255]]], dtype=np.uint8)
WALL_RGB = (0.2, 0.4, 0.6)

OBJ = """mtllib quad.mtl
v 0 0 0
v 2 0 0
v 2 0 -1
v 0 0 -1
v 0 1 -1
v 2 1 -1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl tex
f 1/1 2/2 3/3
f 1/1 3/3 4/4
usemtl plain
f 4 3 6
f 4 6 5
"""

MTL = f"""newmtl tex
Kd 0.8 0.8 0.8
map_Kd quad.png
newmtl plain
Kd {WALL_RGB[0]} {WALL_RGB[1]} {WALL_RGB[2]}
"""


def write_quad(folder: Path, texture: bytes | None = None) -> Path:
    """Write quad.obj, quad.mtl and quad.png (or `texture` bytes) into `folder`; returns the OBJ."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "quad.obj").write_text(OBJ)
    (folder / "quad.mtl").write_text(MTL)
    if texture is None:
        Image.fromarray(TEXELS).save(folder / "quad.png")
    else:
        (folder / "quad.png").write_bytes(texture)
    return folder / "quad.obj"


@pytest.fixture
def quad_dir(tmp_path) -> Path:
    """A user asset folder holding the textured quad."""
    write_quad(tmp_path / "assets")
    return tmp_path / "assets"


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path, monkeypatch):
    """Every test writes its caches under tmp_path and ignores the user's asset folders."""
    monkeypatch.setenv("MORPHOSIM_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("MORPHOSIM_ASSETS", raising=False)
