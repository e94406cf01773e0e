"""`morphosim assets list|search|show`, on a user folder, and one render of a real asset."""

from __future__ import annotations

import json

import imageio.v3 as iio
import numpy as np
import pytest

from morphosim_gym.assets.sources import SweetHome3DSource
from morphosim_gym.cli import main

HORSE = "sweethome3d/blendswap-cc-0/horse2"


def _run(capsys, *argv):
    code = main(["assets", *argv])
    return code, capsys.readouterr()


def test_list_search_show(quad_dir, capsys, tmp_path):
    base = ["--sources", "", "--assets", str(quad_dir)]
    code, out = _run(capsys, "list", *base, "--json")
    assert code == 0
    summary = json.loads(out.out)
    assert summary == {"assets": 1, "sources": {"folder": 1}, "categories": {"object": 1}}
    code, out = _run(capsys, "list", *base)
    assert code == 0 and "per source" in out.out and "folder" in out.out
    code, out = _run(capsys, "search", "quad", *base, "--no-embed")
    assert code == 0 and "folder/assets/quad" in out.out
    code, out = _run(capsys, "search", "giraffe", *base, "--no-embed")
    assert code == 1 and "no asset matches" in out.out
    png = tmp_path / "quad.png"
    code, out = _run(capsys, "show", "folder/assets/quad", *base, "--render", str(png), "--budget", "800",
                     "--width", "48")
    assert code == 0
    info = json.loads(out.out)
    assert info["name"] == "quad" and info["converted"]["gaussians"] == 800
    assert iio.imread(png).shape == (48, 48, 3)
    code, out = _run(capsys, "show", "folder/assets/nothing", *base)
    assert code == 2 and "No asset" in out.err


@pytest.mark.skipif(SweetHome3DSource.discover() is None,
                    reason="Debian sweethome3d-furniture is not installed (/usr/share/sweethome3d/furniture)")
def test_render_a_real_asset(capsys, tmp_path):
    png = tmp_path / "horse.png"
    code, out = _run(capsys, "show", HORSE, "--sources", "sweethome3d", "--render", str(png), "--budget", "6000",
                     "--width", "96")
    assert code == 0
    info = json.loads(out.out)
    ext = info["converted"]["extents_m"]
    assert ext[2] == pytest.approx(2.0, abs=0.02) and ext[1] > ext[0]      # 2 m tall, long along y
    image = iio.imread(png).astype(np.float32) / 255
    drawn = np.abs(image - 0.92).max(axis=2) > 0.1                          # pixels that differ from the backdrop
    assert 0.05 < drawn.mean() < 0.9
    r, _, b = image[drawn].mean(axis=0)
    assert r > b                                                             # a brown horse, not a grey blob
