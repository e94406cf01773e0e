"""One benchmark episode: (suite, policy, perturbation, seed) -> a result record (+ frames).

The record is a flat, JSON-serialisable dict. Everything in it except `wall_s` is a function
of the episode's key, so two backends (or a rerun) produce identical records. Failures are
results too: a perturbation that does not apply, a policy that raises or returns an invalid
action, an env error: `status` is "failed", `error` has the text and `error_stage` says where.
"""

from __future__ import annotations

import math
import time
import traceback
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from morphosim_gym.envs.wrappers import LanguagePerturbation

from ..policies import policy_for_episode
from .perturb import camera_option, resolve_edits, sample_episode, template_values
from .suite import Suite

__all__ = ["EpisodeKey", "EpisodeResult", "EpisodeRunner", "STAGES", "make_sim"]

STAGES = ("suite", "scene", "perturbation", "policy", "env")
_SKIP_INFO = {"success", "step", "t", "scene_seed", "target_id", "edits", "edit_errors", "perturbations"}


@dataclass(frozen=True, order=True)
class EpisodeKey:
    """Which episode: the policy spec as given, the perturbation name ("base" for none), the seed."""

    policy: str
    perturbation: str
    seed: int

    @property
    def id(self) -> str:
        """A string form, unique within a sweep."""
        return f"{self.policy}|{self.perturbation}|{self.seed}"


@dataclass
class EpisodeResult:
    """The record of an episode and, when asked for, its frames [F, H, W, 3] uint8."""

    record: dict
    frames: Optional[np.ndarray] = None


class _Failure(Exception):
    """An episode failure at a stage (carries the text recorded in the results)."""

    def __init__(self, stage: str, message: str) -> None:
        super().__init__(message)
        self.stage = stage


def _text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


def make_sim(suite: Suite, cache_dir: Optional[str]) -> Any:
    """The envs' default `MorphoSim` (`envs.config.DEFAULT_SIM_CONFIG`), caching generated scenes on
    disk under `cache_dir` (None = default)."""
    from dataclasses import replace

    from morphosim_gym.envs.config import DEFAULT_SIM_CONFIG
    from morphosim_gym.pipeline import MorphoSim

    return MorphoSim(replace(DEFAULT_SIM_CONFIG, cache=True, cache_dir=cache_dir))


class EpisodeRunner:
    """Runs episodes of one suite in this process, keeping one env and one `MorphoSim`.

    Args:
        suite: the suite.
        cache_dir: the scene cache shared by all workers (None = `MorphoSim`'s default).
    """

    def __init__(self, suite: Suite, cache_dir: Optional[str] = None) -> None:
        self.suite = suite
        self.sim = make_sim(suite, cache_dir)
        self._env: Any = None

    @property
    def env(self) -> Any:
        """The suite's env (made on first use)."""
        if self._env is None:
            import gymnasium as gym

            import morphosim_gym.envs  # noqa: F401  (registers the ids)

            self._env = gym.make(self.suite.env_id, task=self.suite.task, sim=self.sim, on_edit_error="raise",
                                 disable_env_checker=True, **self.suite.env_kwargs)
        return self._env

    def prepare(self, seed: int) -> str:
        """Generate (or load) the scene of episode `seed` into the cache; returns its prompt."""
        ep = sample_episode(self.suite, seed)
        self.sim.generate(ep.request.prompt, seed=ep.scene_seed)
        return ep.request.prompt

    def run(self, key: EpisodeKey, frames: int = 0) -> EpisodeResult:
        """Run one episode; never raises for episode-level failures (they are in the record)."""
        start = time.perf_counter()
        record: dict[str, Any] = {"policy": key.policy, "perturbation": key.perturbation, "seed": key.seed,
                                  "status": "ok", "error": None, "error_stage": None, "prompt": None,
                                  "scene_seed": None, "target": None, "edits": [], "at": 0, "camera": None,
                                  "success": None, "return": None, "steps": 0, "terminated": False, "perturbed": False,
                                  "metrics": {}}
        strip = None
        try:
            strip = self._episode(key, frames, record)
        except _Failure as exc:
            record.update(status="failed", error=str(exc), error_stage=exc.stage)
        except Exception as exc:  # an env or library error: recorded, the sweep goes on
            tb = traceback.extract_tb(exc.__traceback__)[-1]
            record.update(status="failed", error=f"{_text(exc)} (at {tb.filename.rsplit('/', 1)[-1]}:{tb.lineno})",
                          error_stage="env")
        record["wall_s"] = round(time.perf_counter() - start, 4)
        return EpisodeResult(record, strip)

    # ------------------------------------------------------------------ parts
    def _episode(self, key: EpisodeKey, frames: int, record: dict) -> Optional[np.ndarray]:
        suite = self.suite
        pert = suite.perturbation(key.perturbation)
        if pert.error:
            raise _Failure("suite", pert.error)
        ep = sample_episode(suite, key.seed)
        record.update(prompt=ep.request.prompt, scene_seed=ep.scene_seed, at=pert.at)
        env = self.env
        try:
            scene = self.sim.generate(ep.request.prompt, seed=ep.scene_seed)
            values = template_values(scene, env.unwrapped.task, ep.request)
        except ValueError as exc:
            raise _Failure("scene", _text(exc)) from None
        record["target"] = values["target"]
        try:
            edits = resolve_edits(pert, values)
            camera = camera_option(pert, scene)
        except ValueError as exc:
            raise _Failure("perturbation", _text(exc)) from None
        record.update(edits=list(edits), camera=camera or None)
        options: dict[str, Any] = {"prompt": ep.request.prompt, "scene_seed": ep.scene_seed,
                                   "target": ep.request.target or None, "camera": camera}
        try:
            env = LanguagePerturbation(env, schedule={pert.at: edits} if edits else {})   # the one edit scheduler
        except ValueError as exc:
            raise _Failure("perturbation", _text(exc)) from None
        try:
            obs, info = env.reset(seed=key.seed, options=options)
        except ValueError as exc:
            raise _Failure("perturbation" if edits and pert.at == 0 else "env", _text(exc)) from None
        try:
            act = policy_for_episode(key.policy, env, key.seed)
        except Exception as exc:
            raise _Failure("policy", f"the policy factory raised {_text(exc)}") from None
        return self._loop(env, act, obs, info, pert.at, edits, frames, record)

    def _loop(self, env: LanguagePerturbation, act: Any, obs: Any, info: dict, at: int, edits: tuple[str, ...],
              frames: int, record: dict) -> Optional[np.ndarray]:
        u = env.unwrapped
        horizon = max(int(round(u.world.duration / u.dt)), 1)
        keep = sorted(set(np.round(np.linspace(0, horizon, frames)).astype(int).tolist())) if frames else []
        shots: dict[int, np.ndarray] = {0: obs["rgb"].copy()} if 0 in keep else {}
        total, step = 0.0, 0
        space = env.action_space
        while True:
            try:
                action = act(obs, info)
            except Exception as exc:
                raise _Failure("policy", f"the policy raised {_text(exc)} at step {step}") from None
            a = _check_action(action, space.shape, step)
            step += 1
            try:
                obs, reward, terminated, truncated, info = env.step(a)      # the wrapper applies the edits due
            except ValueError as exc:
                if env.failed is None:
                    raise
                raise _Failure("perturbation", f"{_text(exc)} (before step {step})") from None
            total += float(reward)
            if step in keep:
                shots[step] = obs["rgb"].copy()
            if terminated or truncated:
                break
        record.update(success=bool(info["success"]), steps=step, terminated=bool(terminated),
                      perturbed=bool(edits or record["camera"]) and (at == 0 or step >= at), metrics=_metrics(info))
        record["return"] = total
        if not keep:
            return None
        last = obs["rgb"]                     # an episode that ended early shows its final frame from then on
        return np.stack([shots.get(k, last) for k in keep])


def _check_action(action: Any, shape: tuple, step: int) -> np.ndarray:
    """The action as a float array of the env's shape; `_Failure` for anything else (the env would
    raise too, but the record should say that the policy was at fault)."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        raise _Failure("policy", f"invalid action at step {step}: expected numbers of shape {shape}, found "
                                 f"{action!r}") from None
    if a.shape != tuple(shape):
        raise _Failure("policy", f"invalid action at step {step}: expected shape {tuple(shape)}, found {a.shape}")
    if not np.all(np.isfinite(a)):
        raise _Failure("policy", f"invalid action at step {step}: expected finite values, found {a.tolist()}")
    return a


def _metrics(info: dict) -> dict[str, Any]:
    """The final info's scalar task measurements (JSON-safe)."""
    out: dict[str, Any] = {}
    for k, v in info.items():
        if k in _SKIP_INFO or k.startswith("reward_"):
            continue
        if isinstance(v, (bool, np.bool_)):
            out[k] = bool(v)
        elif isinstance(v, (int, np.integer)):
            out[k] = int(v)
        elif isinstance(v, (float, np.floating)) and math.isfinite(float(v)):
            out[k] = float(v)
    return out
