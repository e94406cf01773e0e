"""The policy protocol, the observation-free built-ins and `resolve_policy` (no MorphoSim env needed)."""

from types import SimpleNamespace

import numpy as np
import pytest
from gymnasium import spaces

from morphosim_gym.policies import (
    BUILTIN_POLICIES,
    POLICY_SPEC_HELP,
    Act,
    PolicyFactory,
    color_policy,
    oracle_policy,
    policy_for_episode,
    random_policy,
    resolve_policy,
    zero_policy,
)

BOX = spaces.Box(-1.0, 1.0, (3,), np.float32)


def box_env(space=BOX):
    return SimpleNamespace(action_space=space, unwrapped=SimpleNamespace())


def forward_factory(env, seed):
    """A factory importable as 'tests.policies.test_policies:forward_factory'."""
    return lambda obs, info: np.full(env.action_space.shape, 0.5, np.float32)


NOT_CALLABLE = 3


def test_builtins_resolve_by_name():
    assert BUILTIN_POLICIES == {"random": random_policy, "zero": zero_policy, "oracle": oracle_policy,
                                "color": color_policy}
    for name, factory in BUILTIN_POLICIES.items():
        assert resolve_policy(name) is factory
        assert isinstance(factory, PolicyFactory)
        assert name in POLICY_SPEC_HELP
    assert "imports" in POLICY_SPEC_HELP and "module:callable" in POLICY_SPEC_HELP


def test_module_callable_and_callables_resolve():
    assert resolve_policy("tests.policies.test_policies:forward_factory") is forward_factory
    assert resolve_policy("morphosim_gym.policies:random_policy") is random_policy
    assert resolve_policy(forward_factory) is forward_factory
    act = resolve_policy("tests.policies.test_policies:forward_factory")(box_env(), 0)
    assert isinstance(act, Act)
    np.testing.assert_array_equal(act(None, {}), [0.5, 0.5, 0.5])


@pytest.mark.parametrize("spec, words", [
    ("nope", ["Expected a policy in ['color', 'oracle', 'random', 'zero'] or 'module:callable'", "'nope'"]),
    ("", ["Expected a policy in", "''"]),
    ("   ", ["Expected a policy in"]),
    (None, ["Expected a policy in", "None"]),
    ("best", ["module:callable", "'best'"]),
    (":f", ["module:callable"]),
    ("tests.policies.test_policies:", ["module:callable"]),
    ("no_such_module_xyz:f", ["import", "no_such_module_xyz", "policy"]),
    ("morphosim_gym.policies:missing", ["missing", "morphosim_gym.policies", "policy"]),
    ("tests.policies.test_policies:forward_factory.nothing", ["found no 'nothing'"]),
    ("tests.policies.test_policies:NOT_CALLABLE", ["callable as factory(env, seed)", "int"]),
])
def test_bad_specs_say_what_is_wrong(spec, words):
    with pytest.raises(ValueError) as err:
        resolve_policy(spec)
    for word in words:
        assert word in str(err.value)


def test_random_policy_draws_the_bench_stream():
    act = random_policy(box_env(), 3)
    first = [act(None, {}) for _ in range(2)]
    # the numbers `morphosim bench --policy random` has always drawn for seed 3: rng([seed, 0xAC7])
    np.testing.assert_allclose(first, [[0.025590969, -0.637153447, 0.634004891],
                                       [-0.319711030, -0.659457624, -0.061475892]], rtol=0, atol=1e-8)
    assert all(a.dtype == np.float32 and BOX.contains(a) for a in first)
    again = random_policy(box_env(), 3)
    np.testing.assert_array_equal([again(None, {}) for _ in range(2)], first)
    other = random_policy(box_env(), 4)
    assert not np.array_equal(other(None, {}), first[0])


def test_random_policy_samples_other_spaces_from_the_seed():
    space = spaces.Discrete(5)
    env = box_env(space)
    draws = [random_policy(env, 1)(None, {}) for _ in range(2)]
    act = random_policy(env, 1)
    seq = [act(None, {}) for _ in range(20)]
    assert draws[0] == draws[1] == seq[0] and all(space.contains(a) for a in seq) and len(set(seq)) > 1
    space.seed(99)
    expected = [space.sample() for _ in range(5)]
    space.seed(99)
    act = random_policy(env, 1)
    act(None, {})
    assert [space.sample() for _ in range(5)] == expected     # the env's own space was left alone (a copy was seeded)


def test_zero_policy():
    act = zero_policy(box_env(), 0)
    a = act(None, {})
    assert a.shape == (3,) and a.dtype == np.float32 and not a.any()
    a[0] = 1.0                                     # a caller may change an action without changing the next
    assert not act(None, {}).any()


@pytest.mark.parametrize("factory, who", [(oracle_policy, "oracle"), (color_policy, "colour")])
def test_task_policies_need_a_morphosim_task(factory, who):
    with pytest.raises(ValueError, match=f"MorphoSim env with a task .* for the {who} policy, found SimpleNamespace"):
        factory(box_env(), 0)


def test_bench_and_view_document_the_same_policy_specs():
    import argparse

    from morphosim_gym.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    for command in ("bench", "view"):
        helps = [a.help for a in sub.choices[command]._actions if "--policy" in a.option_strings]
        assert len(helps) == 1 and POLICY_SPEC_HELP in helps[0], (command, helps)


def old_style(obs, action_space):
    """A viewer policy of the old protocol: an action, not an act."""
    return np.zeros(3, np.float32)


def test_policy_for_episode_calls_the_factory_and_checks_what_it_gives():
    act = policy_for_episode("random", box_env(), 3)
    np.testing.assert_array_equal(act(None, {}), random_policy(box_env(), 3)(None, {}))
    assert policy_for_episode(forward_factory, box_env(), 0)(None, {}).tolist() == [0.5, 0.5, 0.5]
    with pytest.raises(ValueError, match=r"Expected policy 'old_style' to be a factory\(env, seed\) returning "
                                         r"act\(obs, info\), found it returned ndarray"):
        policy_for_episode(old_style, box_env(), 0)
    with pytest.raises(ValueError, match="'tests.policies.test_policies:old_style' to be a factory"):
        policy_for_episode("tests.policies.test_policies:old_style", box_env(), 0)
