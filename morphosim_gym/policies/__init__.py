"""Policies: one protocol, the built-ins, and the resolver every command uses.

A policy is a factory `factory(env, seed) -> act`, called once per episode; `act(obs, info)`
returns the action (see `protocol.py`). Built-ins: `random`, `zero`, `oracle` (scripted per-task
controllers reading the true target) and `color` (finds the target by the instruction's colour
word). `resolve_policy(spec)` turns a built-in name, "module:callable" or a callable into a factory:

    from morphosim_gym.policies import policy_for_episode, resolve_policy
    factory = resolve_policy("oracle")              # check the spec once
    act = policy_for_episode(factory, env, seed)     # after each env.reset(seed=seed)
    action = act(obs, info)
"""

from .basic import random_policy, zero_policy
from .color import color_policy
from .oracles import oracle_policy
from .protocol import Act, PolicyFactory
from .resolve import BUILTIN_POLICIES, POLICY_SPEC_HELP, policy_for_episode, resolve_policy

__all__ = ["Act", "PolicyFactory", "resolve_policy", "policy_for_episode", "BUILTIN_POLICIES", "POLICY_SPEC_HELP",
           "random_policy", "zero_policy", "oracle_policy", "color_policy"]
