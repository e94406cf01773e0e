"""The built-in policies on base scenes: the oracle solves each task, random does not."""

import pytest

from morphosim_gym.bench import EpisodeKey, EpisodeRunner, load_suite
from morphosim_gym.policies import resolve_policy

EPISODES = 20


@pytest.mark.parametrize("suite_name", ["track", "reach", "find"])
def test_oracle_succeeds_and_random_fails_on_base_scenes(suite_name, cache_dir):
    runner = EpisodeRunner(load_suite(suite_name), cache_dir)
    rates = {}
    for policy in ("oracle", "random"):
        recs = [runner.run(EpisodeKey(policy, "base", seed)).record for seed in range(EPISODES)]
        assert all(r["status"] == "ok" for r in recs), [r["error"] for r in recs if r["error"]]
        rates[policy] = sum(r["success"] for r in recs) / EPISODES
    assert rates["oracle"] >= 0.9, rates
    assert rates["random"] < 0.2, rates


def test_policy_specs():
    assert callable(resolve_policy("oracle")) and callable(resolve_policy("morphosim_gym.policies:random_policy"))
    for spec, word in [("nope", "module:callable"), ("no_such_module_xyz:f", "import"),
                       ("morphosim_gym.policies:missing", "missing")]:
        with pytest.raises(ValueError, match=word):
            resolve_policy(spec)


def test_color_policy_sees_the_colour_and_loses_a_recoloured_target(cache_dir):
    runner = EpisodeRunner(load_suite("track"), cache_dir)
    seeds = range(8)
    base = [runner.run(EpisodeKey("color", "base", s)).record for s in seeds]
    recoloured = [runner.run(EpisodeKey("color", "recolor_target", s)).record for s in seeds]
    assert sum(r["success"] for r in base) >= 5
    assert sum(r["success"] for r in recoloured) == 0
    unsupported = EpisodeRunner(load_suite("reach"), cache_dir).run(EpisodeKey("color", "base", 0)).record
    assert unsupported["status"] == "failed" and unsupported["error_stage"] == "policy"
    assert "Track or Find" in unsupported["error"]
