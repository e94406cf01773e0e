"""`resolve_policy`: a policy factory from what a user wrote (a built-in name, "module:callable",
or a callable), the one way the bench, the viewer and the examples turn a spec into a policy."""

from __future__ import annotations

import importlib
from typing import Any

from .basic import random_policy, zero_policy
from .color import color_policy
from .oracles import oracle_policy
from .protocol import Act, PolicyFactory

__all__ = ["BUILTIN_POLICIES", "POLICY_SPEC_HELP", "resolve_policy", "policy_for_episode"]

BUILTIN_POLICIES: dict[str, PolicyFactory] = {
    "random": random_policy,        # uniform actions drawn from the episode seed
    "zero": zero_policy,            # all-zero actions
    "oracle": oracle_policy,        # scripted controller reading the true target (MorphoSim tasks)
    "color": color_policy,          # finds the target by the instruction's colour word (Track, Find)
}

POLICY_SPEC_HELP = (f"a built-in policy ({', '.join(BUILTIN_POLICIES)}) or module:callable, a factory(env, seed) "
                    "-> act(obs, info) -> action called once per episode; module:callable imports that module "
                    "and runs its code")


def _expected(spec: Any) -> ValueError:
    return ValueError(f"Expected a policy in {sorted(BUILTIN_POLICIES)} or 'module:callable', found {spec!r}")


def _import_attr(spec: str) -> Any:
    """The object `spec` ("package.module:name.attr") names; ValueError saying which part is missing."""
    module_name, sep, attr = spec.partition(":")
    if not sep or not module_name.strip() or not attr.strip():
        raise _expected(spec)
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ValueError(f"Expected policy {spec!r} to name a module that can be imported, found "
                         f"{type(exc).__name__}: {exc}") from None
    obj: Any = module
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"Expected module {module_name!r} to define {attr!r} (policy {spec!r}), found no {part!r}")
        obj = getattr(obj, part)
    return obj


def resolve_policy(spec: str | PolicyFactory) -> PolicyFactory:
    """The policy factory named by `spec`: a built-in name (see `BUILTIN_POLICIES`), "module:callable"
    (imported: this runs that module's code), or a factory itself (returned as is)."""
    if callable(spec):
        return spec
    if not isinstance(spec, str) or not spec.strip():
        raise _expected(spec)
    if spec in BUILTIN_POLICIES:
        return BUILTIN_POLICIES[spec]
    factory = _import_attr(spec)
    if not callable(factory):
        raise ValueError(f"Expected policy {spec!r} to be callable as factory(env, seed), found "
                         f"{type(factory).__name__}")
    return factory


def policy_for_episode(spec: str | PolicyFactory, env: Any, seed: int) -> Act:
    """The `act` of one episode: `resolve_policy(spec)(env, seed)`, checked to be callable (a
    function written as `fn(obs, ...) -> action` instead of a factory fails here, by name)."""
    act = resolve_policy(spec)(env, seed)
    if not callable(act):
        raise ValueError(f"Expected policy {getattr(spec, '__name__', spec)!r} to be a factory(env, seed) returning "
                         f"act(obs, info), found it returned {type(act).__name__}")
    return act
