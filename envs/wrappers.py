"""Wrappers: scheduled language perturbations, and the rgb-only view for image policies."""

from __future__ import annotations

import math
from typing import Any, Mapping, Optional, Sequence

import gymnasium as gym
import numpy as np

__all__ = ["LanguagePerturbation", "RGBObservation"]


class LanguagePerturbation(gym.Wrapper):
    """Apply language edits to the scene during episodes, by step or by chance.

    Args:
        env: a MorphoSim env (or a wrapper of one).
        schedule: step number -> edit command (or list of them). Step 0 edits are applied at
            reset (before the first observation); an edit scheduled at step k >= 1 is applied
            just before the k-th `step()` of the episode, so the observation that step returns
            shows it.
        edits: commands drawn from (uniformly) when `probability` fires.
        probability: chance, before each step, of applying one edit drawn from `edits`.
        max_random_edits: at most this many random edits per episode (None: no limit).

    This wrapper is the one scheduler of mid-episode edits; it applies them through the env's
    primitive `env.unwrapped.perturb(text)`. The wrapper's random draws come from its own
    generator, seeded from the reset seed (so the env's own random stream is untouched and
    rollouts stay reproducible). Failed edits follow the env's `on_edit_error`: with "raise"
    the edit's error propagates from `step()` before the env steps, and `failed` holds its
    `(step, text)`. `info["perturbations"]` lists `(step, text, applied)` of this episode.

    Attributes:
        failed: `(step, text)` of the edit that raised in the last `step()`, else None (step-0
            edits are reset options: their errors come from `reset()`).

    Examples:
        >>> env = LanguagePerturbation(gym.make("MorphoSim/Track-v0"),   # doctest: +SKIP
        ...                            schedule={20: "make the ball blue"})
    """

    def __init__(self, env: gym.Env, schedule: Optional[Mapping[int, Any]] = None, edits: Sequence[str] = (),
                 probability: float = 0.0, max_random_edits: Optional[int] = 1) -> None:
        super().__init__(env)
        if not hasattr(env.unwrapped, "perturb"):
            raise ValueError(f"Expected a MorphoSim env (with perturb()), found {type(env.unwrapped).__name__}")
        self._schedule = _check_schedule(schedule)
        self._edits = tuple(edits)
        if not all(isinstance(t, str) and t.strip() for t in self._edits):
            raise ValueError(f"Expected edits as a list of commands (strings), found {edits!r}")
        self._p = _check_probability(probability, bool(self._edits))
        if max_random_edits is not None and (isinstance(max_random_edits, bool) or int(max_random_edits) < 0):
            raise ValueError(f"Expected max_random_edits >= 0 or None, found {max_random_edits!r}")
        self._max = None if max_random_edits is None else int(max_random_edits)
        self._rng = np.random.default_rng()
        self._step = 0
        self._random_count = 0
        self._log: list[tuple[int, str, bool]] = []
        self.failed: Optional[tuple[int, str]] = None

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[Any, dict]:
        if seed is not None:
            self._rng = np.random.default_rng([int(seed), 0x1A46])
        opts = dict(options or {})
        at_reset = self._schedule.get(0, ())
        if at_reset:
            given = opts.get("edits", ())
            given = [given] if isinstance(given, str) else list(given or ())
            opts["edits"] = given + list(at_reset)
        self._step = 0
        self._random_count = 0
        self.failed = None
        obs, info = self.env.reset(seed=seed, options=opts or options)
        applied = set(info.get("edits", ()))
        self._log = [(0, t, t in applied) for t in at_reset]
        info["perturbations"] = tuple(self._log)
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        self._step += 1
        self.failed = None
        for text in self._schedule.get(self._step, ()):
            self._perturb(text)
        if self._p > 0 and (self._max is None or self._random_count < self._max) and self._rng.random() < self._p:
            text = self._edits[int(self._rng.integers(len(self._edits)))]
            self._random_count += 1
            self._perturb(text)
        obs, reward, terminated, truncated, info = self.env.step(action)
        info["perturbations"] = tuple(self._log)
        return obs, reward, terminated, truncated, info

    def _perturb(self, text: str) -> None:
        self.failed = (self._step, text)
        self._log.append((self._step, text, bool(self.env.unwrapped.perturb(text))))
        self.failed = None


def _check_schedule(schedule: Optional[Mapping[int, Any]]) -> dict[int, tuple[str, ...]]:
    out: dict[int, tuple[str, ...]] = {}
    for step, texts in dict(schedule or {}).items():
        if isinstance(step, bool) or not isinstance(step, (int, np.integer)) or step < 0:
            raise ValueError(f"Expected schedule steps as integers >= 0, found {step!r}")
        texts = (texts,) if isinstance(texts, str) else tuple(texts)
        if not texts or not all(isinstance(t, str) and t.strip() for t in texts):
            raise ValueError(f"Expected edit commands (strings) at schedule step {step}, found {texts!r}")
        out[int(step)] = texts
    return out


def _check_probability(probability: float, have_edits: bool) -> float:
    p = float(probability)
    if not (math.isfinite(p) and 0.0 <= p <= 1.0):
        raise ValueError(f"Expected probability in [0, 1], found {probability!r}")
    if p > 0 and not have_edits:
        raise ValueError("Expected a non-empty edits list for probability > 0, found none")
    return p


class RGBObservation(gym.ObservationWrapper):
    """Keep only one image of the observation dict (default `rgb`), as a Box: for image policies
    such as Stable-Baselines3's `CnnPolicy`."""

    def __init__(self, env: gym.Env, key: str = "rgb") -> None:
        super().__init__(env)
        space = env.observation_space
        if not isinstance(space, gym.spaces.Dict) or key not in space.spaces:
            raise ValueError(f"Expected a Dict observation space with key {key!r}, found {space}")
        self._key = key
        self.observation_space = space.spaces[key]

    def observation(self, observation: dict) -> np.ndarray:
        return observation[self._key]
