"""Reconstruction from a clip alone: contract, quality on a small clip, cache, determinism, bad input."""

import os
import signal
import subprocess
import sys
import time
from dataclasses import replace

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.edit.select import MaskAgreementScorer
from morphosim_gym.reconstruct import ReconstructionConfig, quality_report, reconstruct
from morphosim_gym.reconstruct.features import FeatureConfig
from morphosim_gym.reconstruct.fit import FitConfig

SMALL = ms.GenerationConfig(width=48, height=48, num_frames=9, detail=0.5)
FAST = ReconstructionConfig(fit=FitConfig(iterations=120, progress=False),
                            features=FeatureConfig(iterations=60, progress=False), progress=False, cache=False)


@pytest.fixture(scope="module")
def clip():
    sim = ms.MorphoSim(generation=SMALL, reconstruction="oracle")
    return sim.generate_clip("The bus is moving from right to left", seed=0)


@pytest.fixture(scope="module")
def scene(clip):
    return reconstruct(clip, FAST)


def test_scene_contract(clip, scene):
    assert isinstance(scene, ms.Scene4D)
    assert scene.num_frames == clip.num_frames and scene.fps == clip.fps
    assert [o.name for o in scene.objects] == ["road", "bus"]
    assert scene.object("bus").dynamic and not scene.object("road").dynamic
    assert scene.object("road").role == "background"
    assert scene.gaussians.feature_dim == 32 and {"semantic", "color"} <= set(scene.decoders)
    assert scene.motion.num_nodes >= 1 and set(scene.motion.node_objects.tolist()) == {1}


def test_fits_the_input_views_and_the_instances(clip, scene):
    report = quality_report(clip, scene, frame_stride=2)
    assert report["input"]["psnr"] > 26.0            # a short fit on a tiny clip; the bars are for full clips
    assert min(report["instance_iou"].values()) > 0.8
    for name, pr in report["semantic"].items():
        assert pr["precision"] > 0.9 and pr["recall"] > 0.9, name
    # the bus moves in the reconstruction as in the clip
    c0, c1 = scene.object_center("bus", 0.0), scene.object_center("bus", scene.duration)
    g0, g1 = clip.ground_truth.object_center("bus", 0.0), clip.ground_truth.object_center("bus", scene.duration)
    assert np.dot(c1 - c0, g1 - g0) / (np.linalg.norm(c1 - c0) * np.linalg.norm(g1 - g0)) > 0.95


def test_latents_no_pixel_reached_can_be_filled_from_their_neighbours(clip, scene):
    # the bus's underside and far side (completion) are never drawn in front: their latents come
    # from the nearest supervised Gaussians (tests/reconstruct/test_feature_fill.py checks how)
    assert scene._fit_log["features"]["filled"] == 0                 # off by default
    on = reconstruct(clip, replace(FAST, features=replace(FAST.features, fill_unseen=True)))
    assert on._fit_log["features"]["filled"] > 0


def test_edits_select_through_the_feature_field(scene):
    sim = ms.MorphoSim(reconstruction="oracle")
    sel = sim.editor.selector.select(scene, [scene.object("bus").id], "bus")
    assert sel.method == "feature_field"
    truth = scene.gaussians.object_ids == scene.object("bus").id
    precision = (sel.mask & truth).sum() / max(sel.mask.sum(), 1)
    recall = (sel.mask & truth).sum() / truth.sum()
    # the bus is 33 of 2,977 Gaussians in this 48 px fit; its 2D evidence (the feature field queried per
    # pixel) blends road latents around it, so precision varies with the fit's floating-point path:
    # 0.89 on 2026-12-02's machine, >= 0.95 on earlier ones (issue #18: evidence independent of the field).
    assert precision >= 0.85 and recall >= 0.9
    yellow = sim.edit(scene, "make the vehicle yellow")
    assert yellow.undo() is scene


def test_selection_is_judged_by_evidence_not_by_the_gaussians_ids(scene):
    from morphosim_gym.edit.select import Selector

    bus = scene.object("bus").id
    truth = scene.gaussians.object_ids == bus
    sel = Selector().select(scene, [bus], "bus")
    # the 2D evidence tells the thresholds apart (they do not all score the same)
    assert sel.method == "feature_field"
    assert max(s for _, s in sel.scores) - min(s for _, s in sel.scores) > 1e-3
    # the same features with the Gaussians' ids swapped: selection by ids would now pick the road
    others = [o.id for o in scene.objects if o.id != bus]
    ids = scene.gaussians.object_ids.copy()
    ids[truth], ids[np.isin(scene.gaussians.object_ids, others)] = others[0], bus
    swapped = scene.derive(gaussians=scene.gaussians.replace(object_ids=ids))
    sel2 = Selector().select(swapped, [bus], "bus")
    precision = (sel2.mask & truth).sum() / max(sel2.mask.sum(), 1)
    recall = (sel2.mask & truth).sum() / truth.sum()
    assert precision >= 0.85 and recall >= 0.9  # see test_edits_select_through_the_feature_field
    # the best-scoring candidate is kept: a scorer that prefers the worst picks a worse selection. With
    # the instance channel every threshold selects this bus alike, so the names alone are queried here
    names_only = scene.derive(decoders={k: v for k, v in scene.decoders.items() if k != "instance"})
    best = Selector().select(names_only, [bus], "bus")
    worst = Selector(scorer=lambda soft, target: -MaskAgreementScorer()(soft, target)).select(names_only, [bus], "bus")
    iou = lambda m: (m & truth).sum() / max((m | truth).sum(), 1)  # noqa: E731
    assert iou(best.mask) > iou(worst.mask) + 0.05


@pytest.fixture(scope="module")
def sky_clip():
    """The bus clip with real assets: its road setting gets a sky panorama (Blender's, apt blender-data)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.delenv("MORPHOSIM_ASSET_SOURCES", raising=False)
        sim = ms.MorphoSim(generation=SMALL, reconstruction="oracle", cache=False)
        clip = sim.generate_clip("The bus is moving from right to left", seed=0)
    if clip.ground_truth.sky is None:
        pytest.skip("no sky panorama installed (apt blender-data)")
    return clip


def test_the_clips_sky_is_reconstructed_behind_the_gaussians(sky_clip):
    from morphosim_gym.metrics import psnr
    from morphosim_gym.render import render

    clip = sky_clip
    # the sky's pixels have no depth and no instance in the generator's priors
    empty = (clip.depth <= 0) & (clip.masks < 0)
    assert empty.mean() > 0.05
    scene = reconstruct(clip, FAST)
    without = reconstruct(clip, replace(FAST, sky=False))
    assert scene.sky is not None and without.sky is None
    with_sky = quality_report(clip, scene, frame_stride=4)["input"]["psnr"]
    plain = quality_report(clip, without, frame_stride=4)["input"]["psnr"]
    assert with_sky > plain + 10.0                    # 38.4 against 20.3 dB measured
    cam = clip.cameras[0]
    frame = clip.frames[0].astype(np.float32) / 255.0
    assert psnr(render(scene, cam, t=0.0).rgb, frame, mask=empty[0]) > 40.0       # 53.8 dB measured
    # a novel view shows the sky as the truth does, also where the Gaussians do not reach
    novel = cam.orbit(15.0, clip.ground_truth.centre())
    truth = render(clip.ground_truth, novel, t=0.0).rgb
    assert psnr(render(scene, novel, t=0.0).rgb, truth) > psnr(render(without, novel, t=0.0).rgb, truth) + 1.0


def test_deterministic_and_cached(clip, tmp_path):
    cfg = replace(FAST, fit=replace(FAST.fit, iterations=30), features=replace(FAST.features, iterations=10),
                  cache=True, cache_dir=str(tmp_path))
    a = reconstruct(clip, cfg)
    files = list(tmp_path.iterdir())
    assert len(files) == 1 and files[0].suffix == ".msim"
    start = time.perf_counter()
    b = reconstruct(clip, cfg)
    assert time.perf_counter() - start < 2.0                        # loaded, not fitted
    assert b.content_hash() == a.content_hash()
    c = reconstruct(clip, replace(cfg, cache=False))
    assert c.content_hash() == a.content_hash()                     # same seed: same scene


def test_bad_clips_fail_before_any_work(clip):
    no_depth = ms.GeneratedClip(frames=clip.frames, cameras=clip.cameras, fps=clip.fps, masks=clip.masks,
                                labels=clip.labels, tracks=clip.tracks, track_visible=clip.track_visible)
    # a missing prior is estimated from the frames (and the clip's info says so), never refused
    from morphosim_gym.priors import prepare_priors

    filled = prepare_priors(no_depth)
    assert filled.depth is not None and filled.depth.shape == clip.depth.shape and np.any(filled.depth > 0)
    assert filled.info["priors"] == {"depth": "estimated", "masks": "clip", "tracks": "clip"}
    with pytest.raises(ValueError, match="priors"):
        replace(FAST, priors="oracle")
    with pytest.raises(ValueError, match=r"missing \['depth'\]"):
        prepare_priors(no_depth, "ground_truth")
    zero = ms.GeneratedClip(frames=clip.frames, cameras=clip.cameras, fps=clip.fps, depth=np.zeros_like(clip.depth),
                            masks=clip.masks, labels=clip.labels, tracks=clip.tracks, track_visible=clip.track_visible)
    with pytest.raises(ValueError, match="positive depth"):
        reconstruct(zero, FAST)
    with pytest.raises(ValueError, match="GeneratedClip"):
        reconstruct("clip.mclip", FAST)
    with pytest.raises(ValueError, match="finite depth"):
        ms.GeneratedClip(frames=clip.frames, cameras=clip.cameras, fps=clip.fps,
                         depth=np.full(clip.depth.shape, np.nan, np.float32))


@pytest.mark.slow
def test_interrupted_run_leaves_no_cache_entry(clip, tmp_path):
    path = tmp_path / "clip.mclip"
    ms.save_clip(clip, path)
    cache = tmp_path / "cache"
    env = dict(os.environ, MORPHOSIM_CACHE=str(cache))
    # far more iterations than can run before the interrupt, so the signal always lands mid-fit
    proc = subprocess.Popen([sys.executable, "-m", "morphosim_gym.cli", "reconstruct", str(path), "--iterations",
                             "1000000", "--out", str(tmp_path / "out.msim")], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    time.sleep(8.0)
    assert proc.poll() is None, "the reconstruction ended before it could be interrupted"
    proc.send_signal(signal.SIGINT)               # Ctrl-C mid-fit...
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()                               # ...or, harsher, a kill
        proc.wait(timeout=30)
    entries = list(cache.rglob("*.msim")) if cache.exists() else []
    assert entries == []                          # no cache entry, broken or not (temporary files are never read)
    assert not (tmp_path / "out.msim").exists()
    # the next run fits from scratch and caches a readable scene
    ok = subprocess.run([sys.executable, "-m", "morphosim_gym.cli", "reconstruct", str(path), "--iterations", "5", "--feature-iterations", "5",
                         "--out", str(tmp_path / "out.msim")], env=env, capture_output=True, text=True, timeout=600)
    assert ok.returncode == 0, ok.stderr
    assert ms.load_scene(tmp_path / "out.msim").num_frames == clip.num_frames


def test_a_single_frame_or_a_still_clip_gives_the_documented_reduced_result(clip):
    # nothing can be seen to move: the estimated priors hold only the setting, fitted as a static scene
    tiny = replace(FAST, fit=replace(FAST.fit, iterations=10), features=replace(FAST.features, iterations=5),
                   complete_iterations=5)
    for frames, cams in ((clip.frames[:1], clip.cameras[:1]), (np.repeat(clip.frames[:1], 3, 0), clip.cameras[:3])):
        bare = ms.GeneratedClip(frames=frames, cameras=cams, fps=clip.fps, info={"setting": "road"})
        scene = reconstruct(bare, tiny)
        assert [(o.name, o.dynamic) for o in scene.objects] == [("road", False)]
        assert scene._fit_log["priors"] == {"depth": "estimated", "masks": "estimated", "tracks": "estimated"}
