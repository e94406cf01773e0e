"""`SceneWorld`: the target position is computed once per (scene, target, time) for every world
on that scene (pooled scenes serve many episodes and envs), and equals the direct mean."""

import numpy as np

from morphosim_gym.envs.world import SceneWorld


def test_target_position_is_shared_by_worlds_on_one_scene(tiny_scene, monkeypatch):
    ball = next(o for o in tiny_scene.objects if o.name == "ball")
    first = SceneWorld(tiny_scene, ball)
    t = 0.6
    pos = first.target_position(t)
    direct = tiny_scene.at(t).means[tiny_scene.gaussians.object_ids == ball.id].mean(axis=0, dtype=np.float64)
    np.testing.assert_array_equal(pos, direct)
    second = SceneWorld(tiny_scene, ball)                  # another episode or env on the same scene
    monkeypatch.setattr(second, "gaussians", lambda t=None: (_ for _ in ()).throw(AssertionError("recomputed")))
    again = second.target_position(t)
    np.testing.assert_array_equal(again, pos)
    again[:] = 0.0                                         # each caller gets its own copy
    np.testing.assert_array_equal(second.target_position(t), pos)


def test_target_position_follows_the_target_and_an_edited_scene(tiny_scene):
    ball = next(o for o in tiny_scene.objects if o.name == "ball")
    cube = next(o for o in tiny_scene.objects if o.name == "cube")
    assert not np.array_equal(SceneWorld(tiny_scene, ball).target_position(0.5),
                              SceneWorld(tiny_scene, cube).target_position(0.5))
    world = SceneWorld(tiny_scene, ball)
    before = world.target_position(0.5)
    from morphosim_gym.scene import Scene4D

    g = tiny_scene.gaussians.numpy()
    g.means[:] += np.array([0.0, 0.0, 1.0], np.float32)
    moved = Scene4D(g, tiny_scene.motion, tiny_scene.objects, tiny_scene.fps, tiny_scene.cameras)
    world.set_scene(moved)
    np.testing.assert_allclose(world.target_position(0.5) - before, [0.0, 0.0, 1.0], atol=1e-5)
