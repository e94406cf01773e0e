"""The perturbation-axis edits: each parses to its kind, applies as a pure Scene4D -> Scene4D function and
leaves everything it does not target bit-identical; a deliberately broken edit fails the same check."""

from dataclasses import dataclass, field

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.edit import axis_ops
from morphosim_gym.edit.editor import SceneEditor
from tests.conftest import make_tiny_scene

G_FIELDS = ("means", "quats", "scales", "opacities", "colors", "object_ids")


@dataclass
class Allowed:
    """What an edit may change: Gaussian fields on the rows of some objects, nodes, and scene fields."""

    rows: dict = field(default_factory=dict)        # gaussian field -> object ids whose rows may change
    nodes_of: tuple = ()                            # object ids whose scaffold nodes may change
    scene: tuple = ()                               # of: objects, cameras, background, sky, sensor
    appended: bool = False                          # new rows at the end (insert), or rows of `replaced` moved there
    replaced: tuple = ()                            # object ids whose rows are replaced (swap)


def _frozen(scene):
    """A deep copy of every array and field, to check that the input is untouched."""
    return {k: np.array(v, copy=True) for k, v in scene.arrays().items()}, scene.metadata(), scene.content_hash()


def assert_only(before, after, allowed: Allowed) -> None:
    """Everything `allowed` does not name is bit-identical between the scenes."""
    g0, g1 = before.gaussians, after.gaussians
    ids0 = g0.object_ids
    keep = ~np.isin(ids0, list(allowed.replaced))
    n = int(keep.sum())
    if not allowed.appended:
        assert len(g1) == len(g0)
    for f in G_FIELDS + (("features",) if g0.features is not None else ()):
        a, b = getattr(g0, f)[keep], getattr(g1, f)[:n]
        assert b.dtype == a.dtype, f
        free = np.isin(ids0[keep], list(allowed.rows.get(f, ())))
        np.testing.assert_array_equal(a[~free], b[~free], err_msg=f"gaussians.{f} changed outside the target")
    m0, m1 = before.motion, after.motion
    nodes = np.isin(m0.node_objects, list(allowed.nodes_of))
    for f in ("rotations", "translations"):
        a, b = getattr(m0, f), getattr(m1, f)[:, :m0.num_nodes]
        np.testing.assert_array_equal(a[:, ~nodes], b[:, ~nodes], err_msg=f"motion.{f} changed outside the target")
    for f in ("skin_nodes", "skin_weights"):
        np.testing.assert_array_equal(getattr(m0, f)[keep], getattr(m1, f)[:n], err_msg=f"motion.{f} changed")
    np.testing.assert_array_equal(m0.node_objects, m1.node_objects[:m0.num_nodes])
    if "objects" not in allowed.scene:
        assert after.objects[:len(before.objects)] == before.objects
        if not allowed.appended:
            assert after.objects == before.objects
    if "cameras" not in allowed.scene:
        assert after.cameras == before.cameras
    if "background" not in allowed.scene:
        assert after.background == before.background
    if "sky" not in allowed.scene:
        assert (after.sky is None) == (before.sky is None)
        if before.sky is not None:
            np.testing.assert_array_equal(after.sky, before.sky)
    if "sensor" not in allowed.scene:
        assert after.sensor == before.sensor
    assert after.fps == before.fps


BALL, CUBE, GROUND = 1, 2, 0
ALL = (GROUND, BALL, CUBE)
# sentence -> (edit kind, what it may change, a check that it did change what it targets)
CASES = {
    "make the ball twice as big": ("scale", Allowed(rows={"means": (BALL,), "scales": (BALL,)}),
                                   lambda b, a: np.allclose(a.gaussians.scales[100], 2 * b.gaussians.scales[100])
                                   if False else np.allclose(a.gaussians.scales[b.gaussians.object_ids == BALL],
                                                             2 * b.gaussians.scales[b.gaussians.object_ids == BALL])),
    "shrink the cube": ("scale", Allowed(rows={"means": (CUBE,), "scales": (CUBE,)}),
                        lambda b, a: np.ptp(a.gaussians.means[a.gaussians.object_ids == CUBE], 0).max()
                        < np.ptp(b.gaussians.means[b.gaussians.object_ids == CUBE], 0).max()),
    "replace the ball with a red cube": ("swap", Allowed(scene=("objects",), appended=True, replaced=(BALL,)),
                                         lambda b, a: a.object(BALL).category == "cube"),
    "add a blue cube next to the ball": ("insert", Allowed(scene=("objects",), appended=True),
                                         lambda b, a: len(a.objects) == 4 and a.objects[-1].category == "cube"),
    "put a box between the camera and the ball": ("insert", Allowed(scene=("objects",), appended=True),
                                                  lambda b, a: a.objects[-1].category == "box"),
    "dim the lights": ("light", Allowed(rows={"colors": ALL}, scene=("background", "sky")),
                       lambda b, a: a.gaussians.colors.mean() < b.gaussians.colors.mean()),
    "make the light warmer": ("light", Allowed(rows={"colors": ALL}, scene=("background", "sky")),
                              lambda b, a: a.gaussians.colors[:, 0].mean() > b.gaussians.colors[:, 0].mean()),
    "light the scene from the left": ("light", Allowed(rows={"colors": ALL}),
                                      lambda b, a: not np.array_equal(a.gaussians.colors, b.gaussians.colors)),
    "make the sky a sunset": ("sky", Allowed(scene=("sky", "background")), lambda b, a: a.sky is not None),
    "make the ground green": ("recolor", Allowed(rows={"colors": (GROUND,)}),
                              lambda b, a: a.gaussians.colors[a.gaussians.object_ids == GROUND, 1].mean() > 0.3),
    "make the ground checkered": ("texture", Allowed(rows={"colors": (GROUND,)}),
                                  lambda b, a: not np.array_equal(a.gaussians.colors, b.gaussians.colors)),
    "make the ball metallic": ("texture", Allowed(rows={"colors": (BALL,)}),
                               lambda b, a: not np.array_equal(a.gaussians.colors, b.gaussians.colors)),
    "make the cube striped": ("texture", Allowed(rows={"colors": (CUBE,)}),
                              lambda b, a: not np.array_equal(a.gaussians.colors, b.gaussians.colors)),
    "move the scene to snow": ("setting", Allowed(rows={"colors": (GROUND,)}, scene=("sky", "background")),
                               lambda b, a: a.gaussians.colors[a.gaussians.object_ids == GROUND].mean() > 0.8),
    "widen the field of view": ("view", Allowed(scene=("cameras",)),
                                lambda b, a: abs(a.camera.fov_y_deg - 1.3 * b.camera.fov_y_deg) < 1e-6),
    "raise the camera by 1 metre": ("view", Allowed(scene=("cameras",)),
                                    lambda b, a: abs(a.camera.position[2] - b.camera.position[2] - 1.0) < 1e-9),
    "add sensor noise": ("sensor", Allowed(scene=("sensor",)), lambda b, a: a.sensor == (("noise", 0.5),)),
    "blur the images": ("sensor", Allowed(scene=("sensor",)), lambda b, a: a.sensor == (("blur", 0.5),)),
    "compress the images": ("sensor", Allowed(scene=("sensor",)), lambda b, a: a.sensor == (("jpeg", 0.5),)),
    "delay the ball's motion by 1 second": ("delay", Allowed(nodes_of=(BALL,)),
                                            lambda b, a: np.array_equal(a.motion.translations[4, 0],
                                                                        b.motion.translations[0, 0])),
    "make the cube move left": ("redirect", Allowed(nodes_of=(CUBE,)),
                                lambda b, a: not np.array_equal(a.motion.translations, b.motion.translations)),
    "make the ball bigger": ("scale", Allowed(rows={"means": (BALL,), "scales": (BALL,)}),
                             lambda b, a: a.gaussians.scales.sum() > b.gaussians.scales.sum()),
}


@pytest.fixture(scope="module")
def editor():
    return SceneEditor()


@pytest.mark.parametrize("text", list(CASES))
def test_axis_edit_is_pure_and_leaves_the_rest_bit_identical(editor, text):
    kind, allowed, changed = CASES[text]
    scene = make_tiny_scene()
    plan = ms.parse(text, scene=scene)
    assert [e.op for e in plan.edits] == [kind]
    assert type(plan.edits[0]).from_dict(plan.edits[0].to_dict()) == plan.edits[0]     # the JSON form round-trips
    arrays, meta, digest = _frozen(scene)
    out = editor.edit(scene, text)
    # pure: the input is untouched, the output is a new scene whose undo is the input
    assert scene.content_hash() == digest and scene.metadata() == meta
    for k, v in scene.arrays().items():
        np.testing.assert_array_equal(v, arrays[k])
    assert out is not scene and out.undo() is scene and out.history == (text,)
    assert changed(scene, out), f"{text!r} did not change what it targets"
    assert_only(scene, out, allowed)
    ms.render(out, out.camera, 0.5)        # still a valid scene


def test_a_broken_axis_edit_fails_the_check():
    """The check catches an edit of the wrong object: resizing the cube when the ball was asked."""
    scene = make_tiny_scene()
    wrong = axis_ops.scale_objects(scene, scene.gaussians.object_ids == CUBE, 2.0)
    with pytest.raises(AssertionError):
        assert_only(scene, wrong, CASES["make the ball twice as big"][1])
    recolored_ball = axis_ops.texture(scene, scene.gaussians.object_ids == BALL, "checkered")
    with pytest.raises(AssertionError):
        assert_only(scene, recolored_ball, CASES["make the ground checkered"][1])
    lit_and_moved = axis_ops.change_view(axis_ops.light_brightness(scene, 0.6), fov_factor=1.2)
    with pytest.raises(AssertionError):
        assert_only(scene, lit_and_moved, CASES["dim the lights"][1])


def test_axis_edits_that_cannot_apply_say_why(editor):
    scene = make_tiny_scene()
    still = editor.edit(scene, "stop the ball")
    with pytest.raises(ms.EditError, match="does not move"):
        editor.edit(still, "delay the ball's motion by 1 second")
    with pytest.raises(ms.CommandError, match="with a Y"):
        ms.parse("replace the ball", scene=scene)
    with pytest.raises(ms.CommandError, match="where to put"):
        ms.parse("add a box on top of the ball", scene=scene)
    with pytest.raises(ms.EditError):
        editor.edit(scene, "replace the dog with a cube")
    no_ground = editor.edit(scene, "delete the ground")
    with pytest.raises(ms.EditError, match="no ground"):
        editor.edit(no_ground, "move the scene to snow")


def test_swapped_object_keeps_its_motion_and_place(editor):
    scene = make_tiny_scene()
    out = editor.edit(scene, "replace the ball with a cube")
    for t in (0.0, scene.duration):
        np.testing.assert_allclose(out.object_center(BALL, t)[:2], scene.object_center(BALL, t)[:2], atol=0.08)


def test_occluder_hides_the_target_from_the_generation_camera(editor):
    scene = make_tiny_scene()
    before = ms.render(scene, scene.camera, 0.0)
    out = editor.edit(scene, "put a box between the camera and the ball")
    after = ms.render(out, out.camera, 0.0)
    seen = lambda r: int(np.count_nonzero(r.instance == BALL))  # noqa: E731
    assert seen(after) < 0.5 * seen(before)
