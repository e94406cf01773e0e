"""Reconstructed worlds (`reconstruction="fit"`) in every env and in the benchmark: tiny clips, one fit
shared through the on-disk reconstruction cache; edits there select through the feature field."""

from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.envs.pool import build_scenes
from morphosim_gym.reconstruct import ReconstructionConfig
from morphosim_gym.reconstruct.features import FeatureConfig
from morphosim_gym.reconstruct.fit import FitConfig

PROMPT = "a red ball moves from left to right"
TINY_CLIP = ms.GenerationConfig(detail=0.35, num_frames=5, width=32, height=32)
TINY_FIT = ReconstructionConfig(fit=FitConfig(iterations=40, progress=False),
                                features=FeatureConfig(iterations=30, progress=False), complete_iterations=10,
                                progress=False)
ENV_IDS = ("MorphoSim/Track-v0", "MorphoSim/Reach-v0", "MorphoSim/Find-v0")


@pytest.fixture(scope="module")
def fit_sim_config(tmp_path_factory):
    """Fit worlds on tiny clips, reconstructions cached in a folder of this module's own."""
    return ms.SimConfig(reconstruction="fit", reconstruction_config=TINY_FIT, generation=TINY_CLIP, cache=True,
                        cache_dir=str(tmp_path_factory.mktemp("fitcache")))


@pytest.fixture(scope="module")
def fit_scene(fit_sim_config):
    (scene,) = build_scenes(ms.MorphoSim(fit_sim_config), [(PROMPT, 0)], progress=False)   # as the envs build
    return scene


def test_a_fit_world_carries_a_feature_field(fit_scene):
    assert fit_scene.provenance.reconstruction.startswith("fit:")
    assert "semantic" in fit_scene.decoders and fit_scene.gaussians.features is not None
    assert "ball" in fit_scene.object_names


def test_fit_objects_take_the_prompts_colours(fit_sim_config, fit_scene):
    """The clip's labels name the objects; the prompt gives their colours, so instructions and edit
    templates read as in ground-truth worlds ("keep the red ball ...")."""
    from morphosim_gym.tasks import describe_object

    assert describe_object(fit_scene.object("ball")) == "red ball"
    env = gym.make("MorphoSim/Track-v0", prompt=PROMPT, target="ball", scene_seed=0, sim=fit_sim_config,
                   width=32, height=32)
    assert "red ball" in env.reset(seed=0)[1]["instruction"]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_env_runs_in_a_fit_world(env_id, fit_sim_config, fit_scene):
    env = gym.make(env_id, prompt=PROMPT, target="ball", scene_seed=0, sim=fit_sim_config, width=32, height=32)
    obs, info = env.reset(seed=0)
    assert info["scene_id"] == fit_scene.content_hash()           # the cached fit, not a new one
    assert env.unwrapped.scene.provenance.reconstruction.startswith("fit:")
    steps = 0
    while True:
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        steps += 1
        assert np.isfinite(reward)
        if terminated or truncated:
            break
    assert 1 <= steps <= 10


def test_an_edit_in_a_fit_world_selects_through_the_feature_field(fit_sim_config, fit_scene):
    """The env's edit goes through the selector's feature-field query: a selection by the Gaussians'
    object ids (method "object_ids", or no selector call at all) fails this test."""
    env = gym.make("MorphoSim/Track-v0", prompt=PROMPT, target="ball", scene_seed=0, sim=fit_sim_config,
                   width=32, height=32)
    selector = env.unwrapped._sim.editor.selector
    calls = []
    inner = selector.select

    def spy(scene, ids, query, evidence=None):
        sel = inner(scene, ids, query, evidence)
        calls.append(sel)
        return sel

    selector.select = spy
    _, info = env.reset(seed=0, options={"edits": ["make the ball blue"]})
    assert info["edits"] == ("make the ball blue",)
    assert len(calls) == 1 and calls[0].method == "feature_field" and calls[0].relevance is not None
    edited = env.unwrapped.scene
    changed = np.any(edited.gaussians.colors != fit_scene.gaussians.colors, axis=1)
    assert np.array_equal(changed & ~calls[0].mask, np.zeros_like(changed))     # only selected Gaussians changed
    assert changed.any() and edited.gaussians.colors[changed][:, 2].mean() > 0.5
    ball = fit_scene.gaussians.object_ids == fit_scene.object("ball").id       # evaluation only
    assert (calls[0].mask & ball).sum() >= 0.5 * calls[0].mask.sum()


def test_feature_selection_ignores_the_gaussians_ids(fit_scene):
    """The same fitted scene with every Gaussian's id set to the ball's: a selection by ids would take
    the whole scene; the feature field still takes (mostly) the ball."""
    from morphosim_gym.edit.select import Selector

    ball_id = fit_scene.object("ball").id
    truth = fit_scene.gaussians.object_ids == ball_id
    g = fit_scene.gaussians
    scrambled = fit_scene.derive(None, gaussians=ms.Gaussians(means=g.means, quats=g.quats, scales=g.scales, opacities=g.opacities,
                                              colors=g.colors, features=g.features,
                                              object_ids=np.full(len(g), ball_id)))
    sel = Selector().select(scrambled, [ball_id], "ball")
    assert sel.method == "feature_field"
    assert sel.mask.sum() < 0.9 * len(g) and (sel.mask & truth).sum() >= 0.5 * sel.mask.sum()


def test_a_target_not_in_the_fitted_scene_fails_at_make_or_reset(fit_sim_config, fit_scene):
    with pytest.raises(ValueError, match="no target.*'horse'"):
        gym.make("MorphoSim/Track-v0", prompt=PROMPT, target="horse", scene_pool=1, sim=fit_sim_config,
                 width=32, height=32)
    env = gym.make("MorphoSim/Track-v0", prompt=PROMPT, scene_seed=0, sim=fit_sim_config, width=32, height=32)
    with pytest.raises(ValueError, match="'horse'"):
        env.reset(seed=0, options={"target": "horse"})


def test_a_bad_preset_name_fails_at_make():
    with pytest.raises(ValueError, match="preset name in \\['fast', 'full'\\]"):
        gym.make("MorphoSim/Track-v0", sim=ms.SimConfig(reconstruction="fit", reconstruction_config="quick"))


def test_presets_resolve():
    from morphosim_gym.reconstruct.presets import RECONSTRUCTION_PRESETS, resolve_reconstruction_config

    assert resolve_reconstruction_config(None) == ReconstructionConfig()
    assert resolve_reconstruction_config("fast") is RECONSTRUCTION_PRESETS["fast"]
    fast = RECONSTRUCTION_PRESETS["fast"]
    assert fast.fit.iterations < ReconstructionConfig().fit.iterations and not fast.progress
    assert resolve_reconstruction_config(TINY_FIT) is TINY_FIT


def test_a_fit_pool_loads_from_the_reconstruction_cache(fit_sim_config, fit_scene):
    sim = ms.MorphoSim(fit_sim_config)
    (scene,) = build_scenes(sim, [(PROMPT, 0)], workers=2, progress=False, timeout_s=600)
    assert scene.content_hash() == fit_scene.content_hash()


def test_bench_suites_take_fit_worlds(tmp_path):
    from morphosim_gym.bench import load_suite
    from morphosim_gym.bench.episode import make_sim
    from morphosim_gym.bench.suite import SuiteError

    suite = load_suite("smoke")
    fit = suite.with_world(reconstruction="fit", reconstruction_config="fast", generation={"num_frames": 9})
    assert fit.digest() != suite.digest() and suite.world == {}
    sim = make_sim(fit, str(tmp_path))
    assert sim.config.reconstruction == "fit" and sim.config.reconstruction_config == "fast"
    assert sim.config.generation.num_frames == 9 and sim.config.cache
    assert make_sim(suite, None).config.reconstruction == "oracle"
    with pytest.raises(SuiteError, match="world"):
        suite.with_world(reconstruction="fit", reconstruction_config="quick")
    with pytest.raises(SuiteError, match="Unknown key 'detail' in 'world'"):
        load_suite({"name": "x", "env": "MorphoSim/Track-v0", "perturbations": [], "world": {"detail": 1}})


@pytest.mark.slow
def test_a_bench_sweep_runs_in_fit_worlds(tmp_path):
    """Base and recolour episodes of a fixed prompt in fit worlds: the recolour selects by features."""
    from morphosim_gym.bench import load_suite, run_sweep

    suite = load_suite({"name": "fitsmoke", "env": "MorphoSim/Track-v0", "scenes": {"prompt": "a red {object} moves from left to right", "target": "object", "target_color": None,
                                   "fields": {"object": ["ball"]}},
                        "env_kwargs": {"width": 32, "height": 32}, "episodes": 1, "frames": 0,
                        "world": {"reconstruction": "fit", "reconstruction_config": "fast",
                                  "generation": {"num_frames": 5, "width": 32, "height": 32}},
                        "perturbations": [{"name": "recolor", "edits": "make the ball blue"}]})
    result = run_sweep(suite, ["oracle"], tmp_path / "out", cache_dir=str(tmp_path / "cache"), progress=False,
                       report=False)
    assert result.failed == 0, [r["error"] for r in result.records]


@pytest.mark.slow
def test_fit_pool_serial_and_parallel_give_identical_scenes(tmp_path):
    """Full-path determinism of fit worlds: two scenes fitted here one after the other and in two worker
    processes (no cache) are bit-identical."""
    cfg = ms.SimConfig(reconstruction="fit", reconstruction_config=replace(TINY_FIT, cache=False),
                       generation=TINY_CLIP, cache_dir=str(tmp_path))
    sim = ms.MorphoSim(cfg)
    keys = [(PROMPT, 0), ("a blue cube moves from right to left", 1)]
    serial = build_scenes(sim, keys, workers=1, progress=False)
    parallel = build_scenes(sim, keys, workers=2, progress=False, timeout_s=1200)
    assert [s.content_hash() for s in serial] == [s.content_hash() for s in parallel]


@pytest.mark.slow
def test_the_full_size_fit_world(tmp_path):
    """The default fit world: the full reconstruction of the envs' default clip (49 frames, 128 px)."""
    env = gym.make("MorphoSim/Track-v0", prompt=PROMPT, scene_seed=0, scene_pool=1,
                   sim=ms.SimConfig(reconstruction="fit", generation=ms.GenerationConfig(detail=0.35),
                                    cache_dir=str(tmp_path)))
    _, info = env.reset(seed=0, options={"edits": ["make the ball blue"]})
    assert info["edits"] == ("make the ball blue",)
    assert env.unwrapped.scene.provenance.reconstruction.startswith("fit:")
    env.step(env.action_space.sample())
