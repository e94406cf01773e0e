"""One benchmark episode: (suite, policy, perturbation, seed) -> a result record (+ frames, + steps).

The record is a flat, JSON-serialisable dict. Everything in it except `wall_s` is a function
of the episode's key, so two backends (or a rerun) produce identical records. Failures are
results too: a perturbation that does not apply, a policy that raises or returns an invalid
action, an env error: `status` is "failed", `error` has the text and `error_stage` says where.
With `keep_steps=True` the result also carries every step (`EpisodeSteps`: the observation each
action was chosen from, the action as applied, and what the step returned), which
`morphosim collect` writes as training data.
"""

from __future__ import annotations

import math
import time
import traceback
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from morphosim_gym.envs.sensor import SensorEffects
from morphosim_gym.envs.wrappers import LanguagePerturbation

from ..policies import policy_for_episode
from .perturb import camera_option, resolve_edits, sample_episode, template_values
from .suite import Suite

__all__ = ["EpisodeKey", "EpisodeResult", "EpisodeSteps", "EpisodeRunner", "STAGES", "make_sim"]

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
class EpisodeSteps:
    """Every step of an episode, T = steps taken: row t is the observation the t-th action was chosen
    from, that action (clipped to the action space, as the env applied it) and what `step` returned.

    Attributes:
        observations: observation key -> [T, ...] (the env's dtypes).
        actions: [T, A] float32.
        rewards: [T] float32.
        terminated, truncated, success: [T] bool (after the step).
        instructions: T language instructions (`info["instruction"]` of each row's observation).
    """

    observations: dict[str, np.ndarray]
    actions: np.ndarray
    rewards: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    success: np.ndarray
    instructions: list[str]

    def __len__(self) -> int:
        return len(self.actions)


class _NoLog:
    """Keeps no steps (an episode run without `keep_steps`)."""

    def add(self, obs: dict, info: dict, action: np.ndarray, low: np.ndarray, high: np.ndarray) -> None:
        pass

    def result(self, reward: float, terminated: bool, truncated: bool, success: bool) -> None:
        pass


class _StepLog(_NoLog):
    """Collects the rows of `EpisodeSteps` during an episode."""

    def __init__(self) -> None:
        self.obs: list[dict[str, np.ndarray]] = []
        self.rows: list[tuple[np.ndarray, float, bool, bool, bool]] = []
        self.instructions: list[str] = []

    def add(self, obs: dict, info: dict, action: np.ndarray, low: np.ndarray, high: np.ndarray) -> None:
        self.obs.append({k: np.array(v) for k, v in obs.items()})
        self.instructions.append(str(info.get("instruction", "")))
        self.rows.append((np.clip(action, low, high).astype(np.float32), 0.0, False, False, False))

    def result(self, reward: float, terminated: bool, truncated: bool, success: bool) -> None:
        a = self.rows[-1][0]
        self.rows[-1] = (a, float(reward), bool(terminated), bool(truncated), bool(success))

    def steps(self) -> EpisodeSteps:
        keys = self.obs[0].keys() if self.obs else ()
        cols = list(zip(*self.rows)) if self.rows else [[], [], [], [], []]
        return EpisodeSteps({k: np.stack([o[k] for o in self.obs]) for k in keys},
                            np.array(cols[0], np.float32), np.array(cols[1], np.float32), np.array(cols[2], bool),
                            np.array(cols[3], bool), np.array(cols[4], bool), list(self.instructions))


@dataclass
class EpisodeResult:
    """The record of an episode and, when asked for, its frames [F, H, W, 3] uint8 and its steps."""

    record: dict
    frames: Optional[np.ndarray] = None
    steps: Optional[EpisodeSteps] = None


class _Failure(Exception):
    """An episode failure at a stage (carries the text recorded in the results)."""

    def __init__(self, stage: str, message: str) -> None:
        super().__init__(message)
        self.stage = stage


def _text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


def _substitutes(sim: Any, prompt: str) -> bool:
    """Whether the parse of `prompt` substitutes a word (what grounding "exact" refuses)."""
    from morphosim_gym.language.substitutions import plan_substitutions

    return bool(plan_substitutions(sim.parser.parse(prompt)))


def make_sim(suite: Suite, cache_dir: Optional[str], grounding: Optional[str] = None) -> Any:
    """The `MorphoSim` of the suite's worlds (`suite.world` over the envs' default,
    `envs.config.DEFAULT_SIM_CONFIG`), caching generated clips and scenes (and, for fit worlds,
    reconstructions) on disk under `cache_dir` (None = default), parsing at the grounding level
    `grounding` (`SimConfig.grounding`; None: the one in force; "exact" makes a substituted word a
    `CommandError`)."""
    from dataclasses import replace

    from morphosim_gym.pipeline import MorphoSim

    from .suite import world_sim_config

    return MorphoSim(replace(world_sim_config(suite.world), cache=True, cache_dir=cache_dir,
                             grounding=grounding))


class EpisodeRunner:
    """Runs episodes of one suite in this process, keeping one env and one `MorphoSim`.

    Args:
        suite: the suite.
        cache_dir: the scene cache shared by all workers (None = `MorphoSim`'s default).
        grounding: the grounding level of the scene prompts (`SimConfig.grounding`, one of
            `language.grounding.LEVELS`; None: the one in force). Under "exact" a prompt whose words
            the library substitutes ("kangaroo" -> a stand-in) fails its episodes at the "scene"
            stage with the `CommandError`.
    """

    def __init__(self, suite: Suite, cache_dir: Optional[str] = None, grounding: Optional[str] = None) -> None:
        from morphosim_gym.language.grounding import grounding_level

        self.suite = suite
        self.grounding = grounding_level(grounding)
        self.sim = make_sim(suite, cache_dir, self.grounding)
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
        """Generate (or load) the scene of episode `seed` into the cache; returns its prompt. Under
        grounding "exact" a prompt with a substitution is skipped here: its episodes record the
        `CommandError`."""
        from morphosim_gym.envs.pool import build_one

        ep = sample_episode(self.suite, seed)
        if self.grounding == "exact" and _substitutes(self.sim, ep.request.prompt):
            return ep.request.prompt
        build_one(self.sim, ep.request.prompt, ep.scene_seed)      # one thread, as the envs' pools build
        return ep.request.prompt

    def run(self, key: EpisodeKey, frames: int = 0, keep_steps: bool = False) -> EpisodeResult:
        """Run one episode; never raises for episode-level failures (they are in the record).
        `keep_steps=True` keeps every step (`EpisodeResult.steps`; None for a failed episode)."""
        start = time.perf_counter()
        record: dict[str, Any] = {"policy": key.policy, "perturbation": key.perturbation, "seed": key.seed,
                                  "status": "ok", "error": None, "error_stage": None, "prompt": None,
                                  "scene_seed": None, "target": None, "edits": [], "at": 0, "camera": None,
                                  "success": None, "return": None, "steps": 0, "terminated": False, "perturbed": False,
                                  "metrics": {}}
        strip = None
        log = _StepLog() if keep_steps else _NoLog()
        try:
            strip = self._episode(key, frames, record, log)
        except _Failure as exc:
            record.update(status="failed", error=str(exc), error_stage=exc.stage)
        except Exception as exc:  # an env or library error: recorded, the sweep goes on
            tb = traceback.extract_tb(exc.__traceback__)[-1]
            record.update(status="failed", error=f"{_text(exc)} (at {tb.filename.rsplit('/', 1)[-1]}:{tb.lineno})",
                          error_stage="env")
        record["wall_s"] = round(time.perf_counter() - start, 4)
        steps = log.steps() if isinstance(log, _StepLog) and record["status"] == "ok" else None
        return EpisodeResult(record, strip, steps)

    # ------------------------------------------------------------------ parts
    def _episode(self, key: EpisodeKey, frames: int, record: dict, log: _NoLog) -> Optional[np.ndarray]:
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
                                   "target": ep.request.target or None, "camera": camera if pert.at == 0 else {}}
        try:
            env = LanguagePerturbation(SensorEffects(env),                             # the one edit scheduler
                                       schedule={pert.at: edits} if edits else {})
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
        move = camera if pert.at > 0 else {}
        return self._loop(env, act, obs, info, pert.at, edits, frames, record, log, move)

    def _loop(self, env: LanguagePerturbation, act: Any, obs: Any, info: dict, at: int, edits: tuple[str, ...],
              frames: int, record: dict, log: _NoLog, move: Optional[dict] = None) -> Optional[np.ndarray]:
        """Run the episode to its end; `move` (a camera shift due at step `at`) moves the task's camera
        just before that step, as the wrapper applies the edits due then."""
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
            log.add(obs, info, a, space.low, space.high)
            step += 1
            if move and step == at:
                try:
                    u.move_camera(move)
                except ValueError as exc:
                    raise _Failure("perturbation", f"{_text(exc)} (before step {step})") from None
            try:
                obs, reward, terminated, truncated, info = env.step(a)      # the wrapper applies the edits due
            except ValueError as exc:
                if env.failed is None:
                    raise
                raise _Failure("perturbation", f"{_text(exc)} (before step {step})") from None
            total += float(reward)
            log.result(reward, terminated, truncated, info["success"])
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
