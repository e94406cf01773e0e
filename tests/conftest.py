"""Shared fixtures: small deterministic scenes built directly from the scene types."""

import atexit
import os
import shutil
import tempfile

import numpy as np
import pytest

from morphosim_gym.scene import Camera, Gaussians, Motion, Provenance, Scene4D, SceneObject
from morphosim_gym.scene.rotations import axis_angle_to_quat

# The suite's expectations encode the procedural generator; tests of real assets opt in
# (monkeypatch MORPHOSIM_ASSET_SOURCES, see tests/generate/test_real_assets.py).
os.environ.setdefault("MORPHOSIM_ASSET_SOURCES", "")

# Caches of one run, never the machine's ~/.cache: what an earlier run (or a killed one) left there must
# not change a result. The xdist workers inherit the folder from the controller, so they share it.
if "PYTEST_XDIST_WORKER" not in os.environ:
    _CACHE = tempfile.mkdtemp(prefix="morphosim-test-cache-")
    os.environ["MORPHOSIM_CACHE"] = _CACHE
    atexit.register(shutil.rmtree, _CACHE, ignore_errors=True)


def make_tiny_scene(n_per_object: int = 200, frames: int = 9, fps: float = 4.0, seed: int = 0,
                    features: int = 0) -> Scene4D:
    """Ground (static, id 0), a ball sliding along +x (id 1) and a cube spinning about z (id 2)."""
    rng = np.random.default_rng(seed)
    n = n_per_object
    ground = np.c_[rng.uniform(-2, 2, n), rng.uniform(-1, 3, n), np.zeros(n)]
    ball = rng.normal(size=(n, 3))
    ball = 0.3 * ball / np.linalg.norm(ball, axis=1, keepdims=True) + [-1.0, 0.5, 0.3]
    cube = rng.uniform(-0.25, 0.25, (n, 3)) + [1.0, 1.0, 0.25]
    means = np.concatenate([ground, ball, cube])
    ids = np.repeat([0, 1, 2], n)
    colors = np.concatenate([np.tile([0.4, 0.4, 0.4], (n, 1)), np.tile([0.9, 0.1, 0.1], (n, 1)),
                             np.tile([0.1, 0.2, 0.9], (n, 1))])
    g = Gaussians(means=means, quats=rng.normal(size=(3 * n, 4)), scales=rng.uniform(0.03, 0.08, (3 * n, 3)),
                  opacities=rng.uniform(0.6, 1.0, 3 * n), colors=colors, object_ids=ids,
                  features=rng.normal(size=(3 * n, features)) if features else None)
    # node 0: ball, translation along +x; node 1: cube, rotation about its centre
    rot = np.zeros((frames, 2, 4))
    rot[:, 0] = [1, 0, 0, 0]
    rot[:, 1] = axis_angle_to_quat(np.array([0, 0, 1.0]), np.linspace(0, np.pi / 2, frames))
    trans = np.zeros((frames, 2, 3))
    trans[:, 0, 0] = np.linspace(0, 2.0, frames)
    centre = np.array([1.0, 1.0, 0.25])
    from morphosim_gym.scene.rotations import quat_to_matrix
    trans[:, 1] = centre - np.einsum("tij,j->ti", quat_to_matrix(rot[:, 1]), centre)
    node = np.concatenate([np.full(n, -1), np.zeros(n), np.ones(n)])
    motion = Motion.rigid(node, rot, trans, node_objects=np.array([1, 2]))
    objects = (SceneObject(0, "ground", "ground", role="background"),
               SceneObject(1, "ball", "ball", color=(0.9, 0.1, 0.1), dynamic=True),
               SceneObject(2, "cube", "cube", color=(0.1, 0.2, 0.9), dynamic=True))
    cam = Camera.look_at((0, -4, 2), (0, 0.5, 0.3), 64, 64, 60)
    return Scene4D(g, motion, objects, fps, (cam,), provenance=Provenance("a ball and a cube", 0, "test"),
                   background=(0.6, 0.8, 1.0))


@pytest.fixture
def tiny_scene() -> Scene4D:
    return make_tiny_scene()
