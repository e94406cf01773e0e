"""Perturbation axes in the env: every registry axis at reset and mid-episode, the sensor wrapper,
field-of-view edits reaching the rig, and the per-episode axis randomisation."""

import gymnasium as gym
import numpy as np
import pytest

import morphosim_gym  # noqa: F401  (registers the envs)
from morphosim_gym.envs import AxisRandomization, LanguagePerturbation, SensorEffects
from morphosim_gym.envs.sensor import apply_sensor
from morphosim_gym.tasks.axes import AXES, AXIS_FAMILIES, axis_edits, template_values
from morphosim_gym.tasks.randomization import load_randomization, sample_axes

PROMPT = "a red ball moves from left to right next to a blue cube"
KW = dict(prompt=PROMPT, width=32, height=32)


@pytest.fixture(scope="module")
def env():
    e = gym.make("MorphoSim/Track-v0", **KW)
    yield e
    e.close()


def _values(env):
    env.reset(seed=0)
    u = env.unwrapped
    from types import SimpleNamespace
    return template_values(u.scene, u.task, SimpleNamespace(target=None, target_description=None))


def test_registry_has_at_least_twenty_axes_in_known_families():
    assert len(AXES) >= 20 + 8 - 1
    assert {a.family for a in AXES.values()} == set(AXIS_FAMILIES)
    assert len({e for a in AXES.values() for e in a.edits}) == sum(len(a.edits) for a in AXES.values())


def test_every_axis_applies_at_reset(env):
    values = _values(env)
    sensed = SensorEffects(env)                  # the sensor axes act through it
    base_obs, base_info = sensed.reset(seed=0)
    for axis in AXES.values():
        if axis.camera is not None:
            continue
        edits = axis_edits(axis, values)
        obs, info = sensed.reset(seed=0, options={"edits": list(edits)})
        assert info["edits"] == edits and info["edit_errors"] == (), axis.name
        if axis.name not in ("time_offset", "redirect_target", "speed_up_target", "reverse_target_mid",
                             "distractor_motion", "remove_distractor", "recolor_distractor"):
            # a change the first frame shows (motion axes differ later; the distractor may be off-screen)
            assert not np.array_equal(obs["rgb"], base_obs["rgb"]), axis.name


def test_axes_mid_episode_through_the_scheduler(env):
    values = _values(env)
    schedule = {2: list(axis_edits(AXES["light_dim"], values)), 3: list(axis_edits(AXES["sensor_noise"], values))}
    wrapped = LanguagePerturbation(SensorEffects(env), schedule=schedule)
    other = gym.make("MorphoSim/Track-v0", **KW)
    plain = SensorEffects(other)
    obs, _ = wrapped.reset(seed=1)
    ref, _ = plain.reset(seed=1)
    a = np.zeros(env.action_space.shape)
    for step in range(1, 5):
        obs, *_, info = wrapped.step(a)
        ref, *_ = plain.step(a)
        assert np.array_equal(obs["rgb"], ref["rgb"]) == (step < 2), step
    assert [p[1] for p in info["perturbations"]] == schedule[2] + schedule[3]
    assert env.unwrapped.scene.sensor == (("noise", 0.5),)
    other.close()


def test_sensor_effects_are_seeded_and_absent_means_untouched(env):
    s = SensorEffects(env)
    obs, _ = s.reset(seed=0)
    assert s.effects() == {}
    noisy = SensorEffects(env, noise=0.5)
    a, _ = noisy.reset(seed=4)
    b, _ = noisy.reset(seed=4)
    np.testing.assert_array_equal(a["rgb"], b["rgb"])
    assert not np.array_equal(a["rgb"], obs["rgb"])
    img = np.random.default_rng(0).integers(0, 256, (32, 32, 3), dtype=np.uint8)
    rng = np.random.default_rng(0)
    for name in ("blur", "jpeg"):
        out = apply_sensor(img, {name: 0.8}, rng)
        assert out.shape == img.shape and out.dtype == np.uint8 and not np.array_equal(out, img)
    assert np.abs(apply_sensor(img, {"blur": 1.0}, rng).astype(int) - 128).mean() < np.abs(img.astype(int) - 128).mean()
    with pytest.raises(ValueError, match="noise strength"):
        SensorEffects(env, noise=2.0)


def test_field_of_view_edit_reaches_the_rig(env):
    _, base = env.reset(seed=0)
    _, wide = env.reset(seed=0, options={"edits": ["widen the field of view"]})
    assert wide["fov_y_deg"] == pytest.approx(1.3 * base["fov_y_deg"], rel=1e-6)
    _, high = env.reset(seed=0, options={"edits": ["raise the camera by 0.5 metres"]})
    z = lambda info: np.linalg.inv(info["cameras"]["eye"]["world_to_camera"])[2, 3]  # noqa: E731
    assert z(high) == pytest.approx(z(base) + 0.5, abs=1e-6)


def test_randomization_is_seeded_recorded_and_keeps_held_out_axes(env):
    r = AxisRandomization(env, "track")
    draws = [r.reset(seed=s)[1]["randomization"] for s in range(6)]
    again = r.reset(seed=3)[1]
    assert again["randomization"] == draws[3]
    assert any(d["axes"] for d in draws)
    assert not {a for d in draws for a in d["axes"]} & set(r.held_out)
    assert set(again["edits"]) == set(draws[3]["edits"])
    cfg = load_randomization("track")
    values = dict.fromkeys(("target", "target_noun", "new_color", "ground", "swap_noun"), "x")
    values.update(distractor=None, distractor_noun=None, target_color=None)
    many = [sample_axes(cfg, np.random.default_rng(s), values) for s in range(40)]
    assert all(len(d.axes) <= cfg.max_axes for d in many)
    assert any("recolor_distractor" in d.skipped for d in many)           # no distractor: skipped, with the reason
    assert all("needs {distractor}" in why for d in many for why in d.skipped.values())


def test_randomization_config_errors_name_the_key():
    with pytest.raises(ValueError, match="Unknown axis 'nope'"):
        load_randomization({"axes": {"nope": {"p": 0.5}}})
    with pytest.raises(ValueError, match=r"axes.light_dim.p in \[0, 1\]"):
        load_randomization({"axes": {"light_dim": {"p": 2}}})
    with pytest.raises(ValueError, match="held-out"):
        load_randomization({"axes": {"light_dim": {}}, "held_out": ["light_dim"]})
    with pytest.raises(ValueError, match="Unknown field"):
        load_randomization({"axes": {"light_dim": {"edits": "make the light {nope}"}}})
