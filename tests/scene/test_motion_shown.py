"""Nodes shown only at some frames (`Motion.shown`): what is drawn, posed, rendered, saved and edited."""

from __future__ import annotations

import numpy as np
import pytest

from morphosim_gym.edit import ops
from morphosim_gym.render import render
from morphosim_gym.scene import Camera, Gaussians, Motion, Scene4D, SceneObject, load_scene, save_scene

T = 3


def _scene() -> Scene4D:
    """Three blobs side by side, 4 m ahead: blob 0 unbound (always drawn), blob 1 on node 0 (shown
    at frames 0 and 1), blob 2 on nodes 0 and 1 (node 1 shown at frame 2 only: never both)."""
    means = np.array([[-1.0, 4.0, 1.0], [0.0, 4.0, 1.0], [1.0, 4.0, 1.0]])
    g = Gaussians(means=means, quats=np.tile([1.0, 0, 0, 0], (3, 1)), scales=np.full((3, 3), 0.2),
                  opacities=np.full(3, 0.9), colors=[[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]], object_ids=[0, 1, 1])
    nodes = np.array([[-1, -1], [0, -1], [0, 1]])
    weights = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.5]])
    shown = np.array([[True, False], [True, False], [False, True]])
    motion = Motion(np.tile([1.0, 0, 0, 0], (T, 2, 1)), np.zeros((T, 2, 3)), nodes, weights, np.array([1, 1]), shown)
    cam = Camera.look_at((0.0, 0.0, 1.0), (0.0, 4.0, 1.0), width=48, height=32, fov_y_deg=50.0)
    objects = (SceneObject(0, "road", "road", role="background"), SceneObject(1, "person", "person"))
    return Scene4D(g, motion, objects, 1.0, (cam,))


def test_a_gaussian_is_drawn_when_every_node_it_is_bound_to_is_shown_at_the_nearest_frame():
    s = _scene()
    assert s.drawn(0.0).tolist() == [True, True, False]
    assert s.drawn(0.4).tolist() == [True, True, False]          # nearest frame 0
    assert s.drawn(1.6).tolist() == [True, False, False]         # nearest frame 2: node 0 hidden
    assert s.motion.copy(shown=None).drawn(1.0) is None          # no `shown`: everything, every frame


def test_hidden_gaussians_have_no_opacity_in_at_and_are_left_out_of_drawn_at(monkeypatch):
    from morphosim_gym.scene import scene4d

    s = _scene()
    at = s.at(2.0)
    assert np.asarray(at.opacities).tolist() == pytest.approx([0.9, 0.0, 0.0])
    assert s.drawn_at(2.0) is at                                 # a third drawn: more than DRAWN_SUBSET
    monkeypatch.setattr(scene4d, "DRAWN_SUBSET", 0.5)
    drawn = s.drawn_at(2.0)
    assert len(drawn) == 1 and np.asarray(drawn.object_ids).tolist() == [0]
    np.testing.assert_array_equal(drawn.means, at.means[:1])
    assert s.drawn_at(2.0) is drawn                              # cached like `at`
    moved = s.drawn_at(0.0)                                      # two of three drawn: all, hidden at 0 opacity
    assert moved is s.at(0.0)
    plain = Scene4D(s.gaussians, s.motion.copy(shown=None), s.objects, s.fps, s.cameras)
    assert plain.drawn_at(1.0) is plain.at(1.0)


@pytest.mark.parametrize("subset", [0.25, 1.0])       # hidden rows at opacity 0 / left out
def test_a_render_draws_only_what_is_shown(subset, monkeypatch):
    from morphosim_gym.scene import scene4d

    monkeypatch.setattr(scene4d, "DRAWN_SUBSET", subset)
    s = _scene()
    img = np.asarray(render(s, s.camera, t=2.0).rgb)
    only_red = Scene4D(s.gaussians.subset(np.array([0])), Motion.static(1, T), s.objects, s.fps, s.cameras)
    np.testing.assert_allclose(img, np.asarray(render(only_red, s.camera, t=2.0).rgb), atol=1e-6)
    assert img[..., 1].max() < 1e-6 and img[..., 2].max() < 1e-6


def test_an_objects_centre_is_that_of_its_drawn_gaussians():
    s = _scene()
    np.testing.assert_allclose(s.object_center("person", 0.0), [0.0, 4.0, 1.0])
    np.testing.assert_allclose(s.object_center("person", 2.0), [0.5, 4.0, 1.0])    # none drawn: all of it


def test_shown_is_saved_and_kept_by_edits(tmp_path):
    s = _scene()
    back = load_scene(save_scene(s, tmp_path / "s.msim"))
    np.testing.assert_array_equal(back.motion.shown, s.motion.shown)
    removed = ops.remove(s, np.array([True, False, False]))
    np.testing.assert_array_equal(removed.motion.shown, s.motion.shown)
    assert removed.drawn(0.0).tolist() == [True, False]


@pytest.mark.parametrize("shown", [np.ones((T, 3), bool), np.ones((T, 2), np.int32)])
def test_a_shown_table_of_the_wrong_shape_or_type_is_refused(shown):
    m = _scene().motion
    with pytest.raises(ValueError, match="shown"):
        m.copy(shown=shown)
