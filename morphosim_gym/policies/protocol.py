"""The one policy protocol: a factory `factory(env, seed) -> act`, then `act(obs, info) -> action`.

The bench, the viewer and the examples all run policies this way. The factory is called once
per episode, right after the env's reset, with that episode's env and seed (the reset seed), so
a policy carries no state from one episode to the next and two runs from the same seed act the
same. `act` is called once per step with the observation and info the env returned last (the
reset's for the first step) and returns an action of the env's action space.

    def make_policy(env, seed):
        model = load_my_model()                    # cache it at module level in real code
        return lambda obs, info: model.predict(obs, deterministic=True)[0]

    morphosim bench track --policy my_pkg.policies:make_policy
    morphosim view --env MorphoSim/Track-v0 --policy my_pkg.policies:make_policy
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

__all__ = ["Act", "PolicyFactory"]


@runtime_checkable
class Act(Protocol):
    """One episode's policy: the action for the latest observation."""

    def __call__(self, obs: Any, info: dict) -> Any:
        """The action to take now, given the env's latest `obs` and `info` (from reset or step)."""
        ...


@runtime_checkable
class PolicyFactory(Protocol):
    """Makes the policy of one episode."""

    def __call__(self, env: Any, seed: int) -> Act:
        """The policy for an episode of `env` (already reset) whose reset seed is `seed`; the
        same env state and seed must give the same actions."""
        ...
