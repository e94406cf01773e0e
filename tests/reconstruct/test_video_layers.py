"""Motion layers of a video: per-frame layers moved along the flow, a median plate for a still
camera, whole-frame layers for a moving one."""

from __future__ import annotations

import numpy as np
import pytest

from morphosim_gym.priors.depth import ground_plane_depth
from morphosim_gym.reconstruct.video_layers import LayerConfig, LayerPriors, motion_layers, region_flows
from morphosim_gym.render import render
from morphosim_gym.scene import Gaussians, GeneratedClip, Motion, Scene4D, SceneObject
from morphosim_gym.scene.camera_motion import video_cameras

W, H, T, STEP, SIDE = 64, 48, 5, 6, 10          # a 10 px red square walks right 6 px a frame
ROW = 30


def _clip() -> tuple[GeneratedClip, LayerPriors]:
    rng = np.random.default_rng(0)
    tex = np.repeat(np.repeat(rng.integers(60, 200, (H // 4, W // 4, 3), dtype=np.uint8), 4, 0), 4, 1)
    tex[..., 0] //= 2                            # no red in the background
    frames, masks = [], []
    for i in range(T):
        f, m = tex.copy(), np.zeros((H, W), np.int32)
        f[ROW:ROW + SIDE, 8 + STEP * i:8 + STEP * i + SIDE] = (230, 20, 20)
        m[ROW:ROW + SIDE, 8 + STEP * i:8 + STEP * i + SIDE] = 1
        frames.append(f)
        masks.append(m)
    frames = np.stack(frames)
    cams, _ = video_cameras(frames, 50.0, "still")
    depth = np.stack([ground_plane_depth(c) for c in cams]).astype(np.float32)
    return GeneratedClip(frames, tuple(cams), 5.0, prompt="a person walks on a road"), \
        LayerPriors(np.stack(masks), depth, (1,))


def _fitted(clip: GeneratedClip) -> Scene4D:
    """A stand-in for the scaffold fit: two Gaussians, one per object, with 2-d features."""
    g = Gaussians(means=np.array([[0.0, 3.0, 0.0], [0.0, 3.0, 0.3]]), quats=np.tile([1.0, 0, 0, 0], (2, 1)),
                  scales=np.full((2, 3), 0.01), opacities=[0.5, 0.5], colors=[[0.5, 0.5, 0.5], [0.9, 0.1, 0.1]],
                  features=np.array([[1.0, 0.0], [0.0, 1.0]]), object_ids=[0, 1])
    objects = (SceneObject(0, "road", "road", role="background"), SceneObject(1, "person", "person"))
    return Scene4D(g, Motion.static(2, clip.num_frames), objects, clip.fps, (clip.cameras[0],))


def _red(img: np.ndarray) -> np.ndarray:
    return (img[..., 0] > 0.6) & (img[..., 1] < 0.35) & (img[..., 2] < 0.35)


def _rgb(scene: Scene4D, clip: GeneratedClip, t: float) -> np.ndarray:
    return np.clip(np.asarray(render(scene, clip.cameras[0], t=t).rgb), 0, 1)


def test_regions_flow_along_with_their_pixels():
    clip, pri = _clip()
    flow = region_flows(clip.frames, 1, 2, pri.masks[1], 1)
    assert flow[0] == pytest.approx([STEP, 0.0], abs=1.0)


def test_a_time_between_fitted_frames_shows_the_mover_half_way_and_once():
    clip, pri = _clip()
    scene = motion_layers(_fitted(clip), clip, priors=pri)
    assert scene.motion.num_frames == 2 * T - 1 and scene.fps == pytest.approx(2 * clip.fps)
    assert [o.dynamic for o in scene.objects] == [False, True]
    for k in (1, 2):
        mid = _red(_rgb(scene, clip, (k + 0.5) / clip.fps))
        cols = np.nonzero(mid)[1]
        assert cols.mean() + 0.5 == pytest.approx(8 + STEP * (k + 0.5) + SIDE / 2, abs=1.0)
        assert mid.sum() == pytest.approx(SIDE * SIDE, rel=0.25)          # one square, not two neighbours'
        at = _rgb(scene, clip, k / clip.fps)                             # a fitted frame: that frame
        seen = pri.depth[k] > 0                                          # (the sky has no depth: not drawn)
        assert np.abs(at - clip.frames[k] / 255.0)[seen].mean() < 0.03


@pytest.mark.parametrize("between, shows", [("next", (-1,)), ("previous", (1,)), ("both", (-1, 1))])
def test_a_half_step_shows_the_layers_of_the_neighbour_asked_for(between, shows):
    """Frame k's layer is drawn at 2k and, moved half-way, at the half steps `between` names; hidden
    at the others (the default shows one silhouette, the later frame's, not two overlapping)."""
    clip, pri = _clip()
    scene = motion_layers(_fitted(clip), clip, priors=pri, config=LayerConfig(between=between))
    trans, shown = scene.motion.translations, scene.motion.shown
    k0 = trans.shape[1] - T                                   # one layer node per frame, after the fit's
    assert shown[:, :k0].all()                                # the fit's nodes: always
    for k in range(1, T - 1):
        assert set(np.flatnonzero(shown[:, k0 + k]) - 2 * k) == {0, *shows}
        assert np.linalg.norm(trans[2 * k + shows[0], k0 + k]) == pytest.approx(
            np.linalg.norm(_clip_step_world(clip)) / 2, rel=0.2)
    with pytest.raises(ValueError, match="between"):
        motion_layers(_fitted(clip), clip, priors=pri, config=LayerConfig(between="middle"))


def _clip_step_world(clip: GeneratedClip) -> np.ndarray:
    """World displacement of the square's centre over one frame (STEP px at its row's ground depth)."""
    cam = clip.cameras[0]
    depth = float(ground_plane_depth(cam)[ROW + SIDE // 2, 8 + SIDE // 2])
    a = cam.unproject(np.array([8 + SIDE / 2, ROW + SIDE / 2]), np.float64(depth))
    return cam.unproject(np.array([8 + STEP + SIDE / 2, ROW + SIDE / 2]), np.float64(depth)) - a


def test_a_layered_movers_position_is_where_its_frame_shows_it():
    """The scene centre of the mover and an env's target follow the layer drawn at each time (the
    layers of other frames are not drawn then and do not count; they used to sit 10 km away, and
    the target's mean position with them)."""
    from envs.world import SceneWorld

    clip, pri = _clip()
    scene = motion_layers(_fitted(clip), clip, priors=pri)
    world = SceneWorld(scene, scene.object("person"))
    cam = clip.cameras[0]
    for k in range(T):
        px = np.array([8 + STEP * k + SIDE / 2, ROW + SIDE / 2])
        depth = float(pri.depth[k, ROW + SIDE // 2, 8 + STEP * k + SIDE // 2]) * (1 - LayerConfig().layer_offset)
        want = cam.unproject(px, np.float64(depth))
        assert np.linalg.norm(scene.object_center("person", k / clip.fps) - want) < 0.1
        assert np.linalg.norm(world.target_position(k / clip.fps) - want) < 0.1


def test_a_still_camera_gets_the_background_behind_the_movers_from_the_other_frames():
    clip, pri = _clip()
    scene = motion_layers(_fitted(clip), clip, priors=pri)
    img = _rgb(scene, clip, (T - 1) / clip.fps)
    behind = (slice(ROW + 2, ROW + SIDE - 2), slice(10, 8 + SIDE - 2))     # the square at frame 0, gone by then
    assert np.abs(img[behind] - clip.frames[-1][behind] / 255.0).mean() < 0.06
    plain = motion_layers(_fitted(clip), clip, priors=pri, config=LayerConfig(plate=False))
    assert np.abs(_rgb(plain, clip, (T - 1) / clip.fps)[behind] - clip.frames[-1][behind] / 255.0).mean() > 0.1


def test_new_gaussians_carry_their_objects_features_and_ids():
    clip, pri = _clip()
    scene = motion_layers(_fitted(clip), clip, priors=pri)
    g = scene.gaussians
    ids, feats = np.asarray(g.object_ids), np.asarray(g.features)
    assert set(np.unique(ids).tolist()) == {0, 1}
    np.testing.assert_allclose(feats[ids == 1], np.tile([0.0, 1.0], ((ids == 1).sum(), 1)))
    np.testing.assert_allclose(feats[ids == 0], np.tile([1.0, 0.0], ((ids == 0).sum(), 1)))
    # the fitted movers' own Gaussians are gone, every layer Gaussian is bound to one node
    bound = scene.motion.skin_nodes[:, 0] >= 0
    assert np.all(ids[bound] == 1) and bound.sum() == (ids == 1).sum()


def test_a_scene_of_another_clip_is_refused():
    clip, pri = _clip()
    other = GeneratedClip(clip.frames[:3], clip.cameras[:3], clip.fps)
    scene = _fitted(clip)
    with pytest.raises(ValueError, match="fitted to the clip"):
        motion_layers(scene, other, priors=pri)


def test_kept_fitted_movers_keep_their_motion_on_the_half_step_timeline():
    clip, pri = _clip()
    fitted = _fitted(clip)
    rot = np.tile([1.0, 0, 0, 0], (T, 1, 1))
    trans = np.zeros((T, 1, 3))
    trans[:, 0, 0] = np.arange(T) * 0.2                      # the fitted person node walks along x
    motion = Motion(rot, trans, np.array([[-1], [0]]), np.array([[0.0], [1.0]]), np.array([1]))
    fitted = Scene4D(fitted.gaussians, motion, fitted.objects, clip.fps, fitted.cameras)
    scene = motion_layers(fitted, clip, priors=pri, config=LayerConfig(keep_movers=True))
    assert len(np.asarray(scene.gaussians.object_ids)) > len(fitted.gaussians)
    np.testing.assert_allclose(scene.motion.translations[:, 0, 0], np.arange(2 * T - 1) * 0.1, atol=1e-9)
    assert scene.motion.skin_nodes[1, 0] == 0                  # the fitted mover is still bound to it
    dropped = motion_layers(fitted, clip, priors=pri)          # a still camera drops the fit's movers
    assert len(dropped.gaussians) == len(scene.gaussians) - 1


def test_without_movers_a_moving_camera_scene_keeps_its_fitted_timeline():
    """No mover found and no frame layers in a panning clip: the fitted motion and cameras stay as they are
    (the half-step timeline is only for layers; it froze the fit at its first frame and, with one
    camera per frame, failed with "Expected 1 or 1 Cameras, found 7")."""
    clip, pri = _clip()
    cams = tuple(c.orbit(2.0 * i, np.zeros(3)) for i, c in enumerate(clip.cameras))
    clip = GeneratedClip(clip.frames, cams, clip.fps, prompt=clip.prompt)
    rot = np.tile([1.0, 0, 0, 0], (T, 1, 1))
    trans = np.zeros((T, 1, 3))
    trans[:, 0, 0] = np.arange(T) * 0.2                      # the fitted person node walks along x
    motion = Motion(rot, trans, np.array([[-1], [0]]), np.array([[0.0], [1.0]]), np.array([1]))
    fitted = Scene4D(_fitted(clip).gaussians, motion, _fitted(clip).objects, clip.fps, cams)
    scene = motion_layers(fitted, clip, priors=LayerPriors(pri.masks * 0 - 1, pri.depth, ()),
                          config=LayerConfig(frames=False))
    assert len(scene.gaussians) == len(fitted.gaussians) and scene.fps == fitted.fps
    assert scene.cameras == fitted.cameras
    np.testing.assert_allclose(scene.motion.translations[:, 0, 0], np.arange(T) * 0.2)
    np.testing.assert_allclose(scene.object_center("person", scene.duration) - scene.object_center("person", 0.0),
                               fitted.object_center("person", fitted.duration) - fitted.object_center("person", 0.0))


def test_a_region_that_no_shift_matches_better_stays_still():
    clip, pri = _clip()
    flat = np.full_like(clip.frames[:2], 120)                     # nothing to match: every shift ties
    assert np.all(region_flows(flat, 0, 1, pri.masks[0], 1) == 0)
    # a real move wins over staying, unless staying must be beaten by more than it can be
    assert region_flows(clip.frames, 1, 2, pri.masks[1], 1)[0][0] == pytest.approx(STEP, abs=1.0)
    assert np.all(region_flows(clip.frames, 1, 2, pri.masks[1], 1, keep_still=0.0) == 0)


@pytest.mark.slow
def test_on_real_footage_layers_beat_holding_the_previous_frame():
    """vtest.avi (Debian opencv-doc): 15 frames, the layers and plate alone over a stub fit, held-out
    frames rendered half-way between their fitted neighbours score above showing the previous one."""
    from morphosim_gym.reconstruct.video_layers import layer_priors

    from ..footage import vtest_avi

    path = vtest_avi()
    if path is None:
        pytest.skip("install Debian opencv-doc for vtest.avi")
    full = GeneratedClip.from_video(path, fov_deg=45, prompt="people walking on a street", max_frames=15, size=96)
    train = [i for i in range(full.num_frames) if i % 5 != 4]
    held = [i for i in range(full.num_frames) if i % 5 == 4 and i < train[-1]]
    clip = GeneratedClip(full.frames[train], tuple(full.cameras[i] for i in train), full.fps, prompt=full.prompt,
                         info=full.info)
    stub = _fitted(clip)
    scene = motion_layers(stub, clip, priors=layer_priors(clip, stub))

    def psnr(a, b):
        return -10 * np.log10(np.mean((a.astype(np.float64) / 255 - b.astype(np.float64) / 255) ** 2))

    ours, hold = [], []
    for o in held:
        k = train.index(o - 1) + 0.5
        ours.append(psnr((_rgb(scene, clip, k / clip.fps) * 255).round(), full.frames[o]))
        hold.append(psnr(full.frames[o - 1], full.frames[o]))
    assert np.mean(ours) > np.mean(hold), (ours, hold)


def _with_big_background_gaussian(clip: GeneratedClip, row: int, behind: float, size: float) -> Scene4D:
    """The stub fit plus one large cyan background Gaussian centred behind the ground at pixel (W/2, row)
    (by `behind` times its depth): the centre is behind the plate there, its extent reaches farther ground."""
    fitted = _fitted(clip)
    cam = clip.cameras[0]
    z = float(ground_plane_depth(cam)[row, W // 2]) * behind
    centre = cam.unproject(np.array([W / 2, row + 0.5]), np.float64(z))
    g0 = fitted.gaussians
    g = Gaussians(means=np.vstack([g0.means, centre]), quats=np.tile([1.0, 0, 0, 0], (3, 1)),
                  scales=np.vstack([g0.scales, np.full((1, 3), size)]), opacities=[0.5, 0.5, 0.95],
                  colors=np.vstack([g0.colors, [[0.0, 1.0, 1.0]]]), features=np.vstack([g0.features, [[1.0, 0.0]]]),
                  object_ids=[0, 1, 0])
    return Scene4D(g, Motion.static(3, clip.num_frames), fitted.objects, clip.fps, fitted.cameras)


def test_fitted_gaussians_that_cover_the_plate_in_the_input_view_are_dropped():
    clip, pri = _clip()
    row = H - 6
    fitted = _with_big_background_gaussian(clip, row, 1.15, 0.3)
    depth = ground_plane_depth(clip.cameras[0])
    assert depth[row - 6, W // 2] > depth[row, W // 2] * 1.15        # it covers farther ground above its centre
    band = (slice(row - 11, row - 6), slice(W // 2 - 3, W // 2 + 3))
    for keep in (False, True):
        scene = motion_layers(fitted, clip, priors=pri, config=LayerConfig(drop_occluders=not keep, refine_rounds=0))
        err = np.abs(_rgb(scene, clip, 0.0)[band] - clip.frames[0][band] / 255.0).mean()
        assert (err > 0.06) if keep else (err < 0.035), (keep, err)
    assert len(motion_layers(fitted, clip, priors=pri).gaussians) < len(
        motion_layers(fitted, clip, priors=pri, config=LayerConfig(drop_occluders=False)).gaussians)


def test_layers_carry_only_the_movers_pixels_not_the_background_their_masks_cover():
    clip, pri = _clip()
    import cv2

    wide = np.stack([cv2.dilate(m.astype(np.uint8), np.ones((7, 7), np.uint8)) for m in pri.masks]).astype(np.int32)
    pri = LayerPriors(wide, pri.depth, pri.movers)               # masks 3 px wider than the square
    k = 1
    truth = clip.frames[0].copy()                                # the frame half-way between k and k + 1
    truth[:] = np.where(pri.masks[0][..., None] > 0, clip.frames[-1], clip.frames[0])   # background there
    x0 = 8 + STEP * k + STEP // 2
    truth[ROW:ROW + SIDE, x0:x0 + SIDE] = (230, 20, 20)
    margin = (slice(ROW - 3, ROW - 1), slice(x0, x0 + SIDE))     # above the square, inside both masks
    assert np.all(wide[k][margin] > 0) and np.all(wide[k + 1][margin] > 0)
    for level, ok in ((LayerConfig().plate_level, True), (-1.0, False)):
        scene = motion_layers(_fitted(clip), clip, priors=pri, config=LayerConfig(plate_level=level))
        err = np.abs(_rgb(scene, clip, (k + 0.5) / clip.fps)[margin] - truth[margin] / 255.0).mean()
        assert (err < 0.03) if ok else (err > 0.05), (level, err)


def test_a_pixel_a_mover_covers_in_every_frame_still_gets_a_plate():
    clip, pri = _clip()
    masks = pri.masks.copy()
    masks[:, 8:14, 50:56] = 1                                    # a still "mover" masked in every frame
    pri = LayerPriors(masks, pri.depth, pri.movers)
    scene = motion_layers(_fitted(clip), clip, priors=pri)
    for k in (0, T - 1):
        img = _rgb(scene, clip, k / clip.fps)
        assert np.abs(img[9:13, 51:55] - clip.frames[k][9:13, 51:55] / 255.0).mean() < 0.05


def test_layers_of_a_small_mover_decode_as_it_and_an_edit_of_it_selects_them():
    """The fit's person Gaussians mostly learned a road-heavy blend (as a few walkers over a large
    street do): the layers take the latent that reads as "person", so recolouring the person
    changes the layers (the mean latent would read as "road" and select nothing)."""
    import morphosim_gym as ms
    from morphosim_gym.language import embeddings

    clip, pri = _clip()
    road, person = embeddings.embed(["road", "person"])
    d = len(road)
    feats = np.stack([road, 0.75 * road + 0.25 * person, 0.75 * road + 0.25 * person, person])
    g = Gaussians(means=np.array([[0.0, 3.0, 0.0], [0.0, 3.0, 0.3], [0.05, 3.0, 0.3], [0.1, 3.0, 0.3]]),
                  quats=np.tile([1.0, 0, 0, 0], (4, 1)), scales=np.full((4, 3), 0.01), opacities=np.full(4, 0.5),
                  colors=np.full((4, 3), 0.5), features=feats, object_ids=[0, 1, 1, 1])
    objects = (SceneObject(0, "road", "road", role="background"), SceneObject(1, "person", "person"))
    decoder = ms.scene.FeatureDecoder("semantic", [np.eye(d)], [np.zeros(d)], normalize=True)
    fitted = Scene4D(g, Motion.static(4, clip.num_frames), objects, clip.fps, (clip.cameras[0],),
                     decoders={"semantic": decoder})
    scene = motion_layers(fitted, clip, priors=pri)
    ids = np.asarray(scene.gaussians.object_ids)
    sim = decoder.similarity(np.asarray(scene.gaussians.features)[ids == 1], embeddings.embed(["road", "person"]))
    assert np.all(sim[:, 1] > sim[:, 0])
    red = ms.MorphoSim().edit(scene, "make the person red")
    changed = np.any(np.asarray(red.gaussians.colors) != np.asarray(scene.gaussians.colors), axis=1)
    assert changed.sum() >= 0.9 * (ids == 1).sum() and not changed[ids == 0].any()


def test_a_fast_mover_is_found_beyond_the_fixed_window_from_its_coarse_match():
    """A 10 px square moving 14 px a frame, searched +- 8 px: found only around its half-resolution match."""
    from morphosim_gym.reconstruct.video_layers import coarse_guesses

    rng = np.random.default_rng(1)
    tex = np.repeat(np.repeat(rng.integers(60, 200, (H // 4, W // 4, 3), dtype=np.uint8), 4, 0), 4, 1)
    frames, labels = np.stack([tex, tex]), np.zeros((H, W), np.int32)
    for i, x in enumerate((10, 24)):
        frames[i, ROW:ROW + SIDE, x:x + SIDE] = (230, 20, 20)
    labels[ROW:ROW + SIDE, 10:10 + SIDE] = 1
    guess = coarse_guesses(frames, 0, 1, labels, 1, search=8)
    assert np.abs(guess[0] - [14, 0]).max() <= 2                     # a rough guess
    assert region_flows(frames, 0, 1, labels, 1, search=8, guess=guess)[0] == pytest.approx([14, 0], abs=0.5)
    assert np.abs(region_flows(frames, 0, 1, labels, 1, search=8)[0][0] - 14) > 5
    with pytest.raises(ValueError, match="guess"):
        region_flows(frames, 0, 1, labels, 1, guess=np.zeros((2, 2)))


PAN = 3.0          # degrees the camera turns a frame in the panning clip


def _panorama(camera) -> np.ndarray:
    """[H, W, 3] in [0, 1]: smooth colour waves (~13 px) over the viewing directions, far away."""
    rows, cols = np.mgrid[:camera.height, :camera.width]
    d = camera.unproject(np.stack([cols + 0.5, rows + 0.5], -1), np.ones((camera.height, camera.width))) - camera.position
    azimuth, elevation = np.arctan2(d[..., 0], d[..., 1]), np.arctan2(d[..., 2], np.hypot(d[..., 0], d[..., 1]))
    phase = np.array([0.0, 2.0, 4.0])
    return 0.5 + 0.2 * np.sin(25.0 * azimuth[..., None] + phase) + 0.2 * np.cos(20.0 * elevation[..., None] - phase)


def _pan_clip() -> tuple[GeneratedClip, LayerPriors]:
    """A camera turning PAN degrees a frame in front of a far, smooth panorama (every frame exact),
    and its priors (all "road", depth 6 m)."""
    from morphosim_gym.scene import Camera

    base = Camera.look_at((0.0, 0.0, 1.0), (0.0, 1.0, 1.0), width=W, height=H, fov_y_deg=50.0)
    cams = tuple(base.orbit(PAN * i, base.position) for i in range(T))
    frames = np.stack([(_panorama(c) * 255 + 0.5).astype(np.uint8) for c in cams])
    clip = GeneratedClip(frames, cams, 5.0, prompt="a person walks on a road")
    return clip, LayerPriors(np.zeros((T, H, W), np.int32), np.full((T, H, W), 6.0, np.float32), ())


def test_a_moving_camera_shows_each_frame_turned_by_the_camera_between_fitted_frames():
    """Frame layers: a fitted frame's view draws its frame; the view half-way between two fitted
    frames draws the earlier one turned by the camera, much closer to the truth there than the
    earlier frame as it is (what holding it would show). Without them the stub fit shows nothing.
    (What the turn brings into view at the edge only the fit can show: left out.)"""
    from morphosim_gym.scene.camera_motion import slerp_cameras

    clip, pri = _pan_clip()
    scene = motion_layers(_fitted(clip), clip, priors=pri)
    bare = motion_layers(_fitted(clip), clip, priors=pri, config=LayerConfig(frames=False))
    assert scene.motion.num_frames == 2 * T - 1 and len(scene.cameras) == 2 * T - 1
    for k in range(T):
        assert np.abs(_rgb_at(scene, clip.cameras[k], k / clip.fps) - clip.frames[k] / 255.0).mean() < 0.01
    inner = np.s_[:, 4:-4]                   # the columns a half step's turn (1.4 px) keeps in view
    for k in range(T - 1):
        cam = slerp_cameras(clip.cameras, list(range(T)), k + 0.5)
        want = _panorama(cam)[inner]
        layer = np.abs(_rgb_at(scene, cam, (k + 0.5) / clip.fps)[inner] - want).mean()
        hold = np.abs(clip.frames[k][inner] / 255.0 - want).mean()
        assert layer < 0.5 * hold, (k, layer, hold)
        assert np.abs(_rgb_at(bare, cam, (k + 0.5) / clip.fps)[inner] - want).mean() > 2 * hold


def test_frame_layers_drop_the_fits_movers_and_what_a_frame_sorts_in_front_of_its_layer():
    clip, pri = _pan_clip()
    g = Gaussians(means=np.array([[0.0, 3.0, 1.0], [0.0, 9.0, 1.0], [0.0, 9.0, 1.2]]),
                  quats=np.tile([1.0, 0, 0, 0], (3, 1)), scales=np.full((3, 3), 0.05), opacities=np.ones(3),
                  colors=np.full((3, 3), 0.5), object_ids=[0, 0, 1])      # road in front, road behind, person
    objects = (SceneObject(0, "road", "road", role="background"), SceneObject(1, "person", "person"))
    fitted = Scene4D(g, Motion.static(3, T), objects, clip.fps, clip.cameras)
    pri = LayerPriors(pri.masks, pri.depth, (1,))
    kept = {len(motion_layers(fitted, clip, priors=pri, config=LayerConfig(drop_occluders=d, refine_rounds=0,
                                                                               keep_movers=m)).gaussians)
            for d, m in ((True, None), (False, None), (False, True))}
    layer_count = T * H * W
    assert kept == {layer_count + 1, layer_count + 2, layer_count + 3}


def _rgb_at(scene: Scene4D, camera, t: float) -> np.ndarray:
    return np.clip(np.asarray(render(scene, camera, t=t).rgb), 0, 1)
