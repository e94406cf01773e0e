"""A wall standing on the floor where a frame's colour changes from floor to wall (`walls`)."""

import numpy as np

from morphosim_gym.priors import RGBPriorEstimators
from morphosim_gym.priors.depth import ground_plane_depth, wall_depth
from morphosim_gym.scene import Camera

H = W = 128
WALL_Y = 2.0                                 # the wall: the world plane y = 2, facing the camera
FLOOR, WALL = (140, 100, 60), (215, 210, 195)


def _scene():
    cam = Camera.look_at((0.0, -3.0, 2.0), (0.0, 0.0, 0.5), width=W, height=H, fov_y_deg=60.0)   # looking down 27 deg
    jj, ii = np.moveaxis(cam.pixel_centres(), -1, 0)
    dirs = np.stack([(jj - cam.cx) / cam.fx, (ii - cam.cy) / cam.fy, np.ones_like(jj)], -1) @ cam.camera_to_world[:3, :3].T
    origin = cam.camera_to_world[:3, 3]
    to_wall = (WALL_Y - origin[1]) / dirs[..., 1]                 # camera depth of the wall along each ray
    floor = ground_plane_depth(cam, 0.0, 1e6)
    shows_floor = (floor > 0) & (floor < to_wall)
    rng = np.random.default_rng(0)
    frame = np.where(shows_floor[..., None], FLOOR, WALL) + rng.normal(0, 5, (H, W, 3))
    return cam, np.clip(frame, 0, 255).astype(np.uint8), shows_floor, to_wall


def test_the_wall_stands_where_the_floor_ends():
    cam, frame, shows_floor, to_wall = _scene()
    masks = np.zeros((1, H, W), np.int32)                          # all setting
    depth = RGBPriorEstimators(backdrop=True, walls=True).depth(frame[None], cam, masks)[0]
    wall = ~shows_floor
    ratio = depth[wall] / to_wall[wall]
    assert abs(np.median(ratio) - 1.0) < 0.03 and np.percentile(np.abs(ratio - 1.0), 95) < 0.06
    # the floor keeps the ground plane's depth
    np.testing.assert_allclose(depth[shows_floor], ground_plane_depth(cam)[shows_floor], rtol=1e-6)
    # off (the default): the floor goes on behind the wall and the rest is a far backdrop
    far = RGBPriorEstimators(backdrop=True).depth(frame[None], cam, masks)[0]
    assert np.median(far[wall] / to_wall[wall]) > 2.0


def test_wall_depth_from_a_given_seam():
    cam, _, shows_floor, to_wall = _scene()
    seam = np.argmax(shows_floor, axis=0)                          # the first floor row per column
    ground = ground_plane_depth(cam)
    depth = wall_depth(cam, seam, ground)
    above = np.arange(H)[:, None] < seam[None, :]
    assert np.all(depth[~above] == 0) and np.all(depth[above] > 0)
    np.testing.assert_allclose(depth[above], to_wall[above], rtol=0.05)
    # columns whose seam meets no ground take their neighbours' wall; none at all: no wall
    lost = seam.copy()
    lost[:20] = 0
    np.testing.assert_allclose(wall_depth(cam, lost, ground)[:, 30:], depth[:, 30:], rtol=1e-5)
    assert not wall_depth(cam, np.zeros(W, np.int64), ground).any()


def test_settings_closed_by_walls_get_them():
    """`prepare_priors` stands walls in a table's or a room's clip (and says so in its info, for
    the fit: `reconstruct.pipeline.NEAR_WALL_FOOTPRINTS`), never under an open sky."""
    import morphosim_gym as ms
    from morphosim_gym.priors import default_estimators, prepare_priors

    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=48, height=48, num_frames=5, detail=0.5))
    table = sim.generate_clip("a blue mug slides slowly across the table from left to right", seed=0)
    road = sim.generate_clip("The bus is moving from right to left", seed=0)
    assert default_estimators(table).walls and not default_estimators(road).walls
    assert prepare_priors(table, "estimated").info["prior_walls"] is True
    assert prepare_priors(road, "estimated").info["prior_walls"] is False
    assert "prior_walls" not in prepare_priors(table, "ground_truth").info
