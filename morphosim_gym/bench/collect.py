"""`morphosim collect`: run a policy (the scripted oracles are the experts) over a suite's base and
counterfactual episodes, or a task's episodes, and write them as a LeRobot v3.0 dataset.

    from morphosim_gym.bench.collect import run_collect
    result = run_collect(load_suite("smoke"), ["oracle"], "out/data/smoke")

Episodes run through the benchmark's own machinery (`EpisodeRunner` with `keep_steps=True` on the
local or Ray backend), so an episode is the same function of its key as in `morphosim bench`.
Resuming works as the bench's does: each finished episode's steps are staged atomically under
`.staging/` and then its record is appended (fsync'd) to `results.jsonl`; a rerun runs only the
episodes without a record. When every episode is done, the dataset files (`meta/`, `data/`,
`videos/`) are written from the staged episodes in plan order, `meta/info.json` last. So a run
killed at any point loses no finished episode, duplicates none, and its folder either has a
complete dataset (an info.json) or a partial run that the same command finishes. A folder of
another run (other suite settings, policies or video settings) is refused.

Each episode's row in `meta/episodes/` also names its policy, perturbation, seed, prompt, edits
and the `base_episode_index` of its unperturbed twin (same policy and seed), so the pairs of a
counterfactual dataset can be rebuilt. Failed episodes are logged (and not rerun) but not written.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence

from ..policies import resolve_policy
from .backends import BACKENDS, run_backend
from .dataset import CODEBASE_VERSION, EpisodeInput, VideoSettings, save_staged, staged_path, write_dataset
from .dataset.features import FrameSchema
from .episode import EpisodeKey, EpisodeRunner
from .layout import RESULTS_LOG
from .runner import plan_episodes
from .store import ResultStore, atomic_write_bytes
from .suite import BASE, Suite, SuiteError, load_suite

__all__ = ["run_collect", "CollectResult", "task_suite", "COLLECT_MANIFEST", "episode_columns"]

COLLECT_MANIFEST = "collect.json"


@dataclass
class CollectResult:
    """What a collection produced."""

    out: Path
    info: dict                      # meta/info.json
    ran: int                        # episodes run by this call
    resumed: int                    # episodes found done in the log
    failed: int                     # episodes that failed (logged, not in the dataset)
    wall_s: float

    @property
    def episodes(self) -> int:
        return int(self.info["total_episodes"])

    @property
    def frames(self) -> int:
        return int(self.info["total_frames"])


def task_suite(task: str, episodes: int = 10, seed: int = 0, env_kwargs: Optional[Mapping[str, Any]] = None) -> Suite:
    """A suite of a task's episodes alone (no perturbations): a built-in task name or a task YAML."""
    from morphosim_gym.envs import env_id_of
    from morphosim_gym.tasks import load_task_spec

    try:
        spec = load_task_spec(task)
    except ValueError as exc:
        raise SuiteError(f"Expected a task name or task YAML file, found {task!r}: {exc}") from None
    ref = str(Path(task).resolve()) if Path(task).suffix in (".yaml", ".yml") else task
    return load_suite({"name": spec.name, "env": env_id_of(spec.kind), "task": ref, "seed": seed, "episodes": episodes,
                       "frames": 0, "env_kwargs": dict(env_kwargs or {}), "perturbations": []})


def _manifest(suite: Suite, policies: Sequence[str], video: VideoSettings) -> dict:
    return {"format": "lerobot", "codebase_version": CODEBASE_VERSION, "suite": suite.name, "digest": suite.digest(),
            "env": suite.env_id, "policies": list(policies), "video": asdict(video)}


def _check_manifest(out: Path, mine: dict) -> None:
    path = out / COLLECT_MANIFEST
    if not path.exists():
        found = sorted(p.name for p in out.iterdir())
        if found:               # the dataset write replaces data/, videos/, meta/: never in someone else's folder
            raise SuiteError(f"{out} is not empty ({found[:3]}) and not a morphosim collect folder (no "
                             f"{COLLECT_MANIFEST}); use an empty or new --out")
        atomic_write_bytes(path, (json.dumps(mine, indent=2) + "\n").encode())
        return
    try:
        theirs = json.loads(path.read_text())
    except json.JSONDecodeError:
        theirs = {}
    diff = [k for k in mine if theirs.get(k) != mine[k]]
    if diff:
        raise SuiteError(f"{out} holds a dataset of another run (suite {theirs.get('suite')!r}, policies "
                         f"{theirs.get('policies')}; differs in {diff}); resume only the same run, or use another "
                         "--out")


def _schema(suite: Suite, cache_dir: Optional[str]) -> tuple[FrameSchema, int, str]:
    """The frame schema, fps and robot type of the suite's env (made once here: bad env_kwargs stop the run)."""
    try:
        env = EpisodeRunner(suite, cache_dir).env
    except (TypeError, ValueError) as exc:
        raise SuiteError(f"Invalid env or env_kwargs in suite {suite.source}: {type(exc).__name__}: {exc}") from None
    try:
        hz = float(env.unwrapped.config.control_hz)
        if hz != round(hz):
            raise SuiteError(f"Expected an integer control_hz (the dataset's fps) in suite {suite.source}, found {hz}")
        return FrameSchema.from_env(env), int(round(hz)), type(env.unwrapped.rig).__name__
    finally:
        env.close()


def episode_columns(record: dict, base_index: int) -> dict[str, Any]:
    """The MorphoSim columns of an episode's row in `meta/episodes/` (from its run record)."""
    return {"policy": record["policy"], "perturbation": record["perturbation"], "seed": int(record["seed"]),
            "base_episode_index": int(base_index), "prompt": record["prompt"] or "",
            "scene_seed": int(record["scene_seed"]), "target": record["target"] or "", "edits": list(record["edits"]),
            "edit_step": int(record["at"]), "camera_shift": json.dumps(record["camera"]) if record["camera"] else "",
            "perturbed": bool(record["perturbed"]), "success": bool(record["success"]),
            "episode_return": float(record["return"])}


def _inputs(out: Path, plan: list[EpisodeKey], done: dict[str, dict]) -> list[EpisodeInput]:
    """The dataset's episodes: the successful runs in plan order, each with its base twin's index."""
    ok = [k for k in plan if done[k.id]["status"] == "ok"]
    missing = [k.id for k in ok if not staged_path(out, k).exists()]
    if missing:
        raise SuiteError(f"{out} logs {len(missing)} episodes whose staged steps are gone (first {missing[0]!r}, "
                         f"expected under {staged_path(out, ok[0]).parent}); "
                         "collect again into a new --out")
    index = {k.id: i for i, k in enumerate(ok)}
    return [EpisodeInput(staged_path(out, k), episode_columns(done[k.id],
                                                              index.get(EpisodeKey(k.policy, BASE, k.seed).id, -1)))
            for k in ok]


def _check_args(backend: str, policies: Sequence[str], video: VideoSettings) -> None:
    if backend not in BACKENDS:
        raise ValueError(f"Expected backend in {BACKENDS}, found {backend!r}")
    if not policies or len(set(policies)) != len(policies):
        raise ValueError(f"Expected one or more distinct policies, found {list(policies)!r}")
    for spec in policies:
        resolve_policy(spec)                            # an unknown policy stops the run before it starts
    video.available()


def _run_pending(out: Path, suite: Suite, pending: list[EpisodeKey], done: dict[str, dict], backend: str,
                 workers: int, cache_dir: Optional[str], address: Optional[str], bar: Any) -> None:
    """Run `pending`, staging each episode's steps and then logging its record (so logged => staged)."""
    jobs = [(k, 0, True) for k in pending]
    with ResultStore(out / RESULTS_LOG) as store:
        for res in run_backend(backend, suite, sorted({k.seed for k in pending}), jobs, cache_dir, workers, address):
            key = EpisodeKey(res.record["policy"], res.record["perturbation"], res.record["seed"])
            if res.steps is not None:
                save_staged(staged_path(out, key), res.steps)
            record = dict(res.record, key=key.id, frames=len(res.steps) if res.steps is not None else 0)
            store.append(record)
            done[key.id] = record
            if bar is not None:
                bar.update(1)


def run_collect(suite: Suite, policies: Sequence[str], out: str | Path, backend: str = "local", workers: int = 1,
                cache_dir: Optional[str] = None, address: Optional[str] = None, progress: bool = True,
                video: VideoSettings = VideoSettings()) -> CollectResult:
    """Run (or resume) the episodes of `suite` for each policy spec and write the dataset to `out`."""
    _check_args(backend, policies, video)
    schema, fps, robot = _schema(suite, cache_dir)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _check_manifest(out, _manifest(suite, policies, video))
    start = time.perf_counter()
    done = ResultStore(out / RESULTS_LOG).load()
    plan = plan_episodes(suite, policies)
    pending = [k for k in plan if k.id not in done]
    bar = _progress(len(plan), len(plan) - len(pending), suite.name, backend) if progress else None
    try:
        _run_pending(out, suite, pending, done, backend, workers, cache_dir, address, bar)
    finally:
        if bar is not None:
            bar.close()
    info = write_dataset(out, schema, fps, _inputs(out, plan, done), video, robot_type=robot)
    failed = sum(done[k.id]["status"] != "ok" for k in plan)
    return CollectResult(out, info, len(pending), len(plan) - len(pending), failed, time.perf_counter() - start)


def _progress(total: int, initial: int, name: str, backend: str):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=f"collect {name} [{backend}]", unit="ep", dynamic_ncols=True)
