"""A benchmark sweep: plan the episodes, skip those already done, run the rest, write the outputs.

    from morphosim_gym.bench import load_suite, run_sweep
    result = run_sweep(load_suite("smoke"), ["oracle", "random"], "out/smoke")
    result.failed          # episodes recorded as failed (the CLI's exit code)

The output folder holds `results.jsonl` (the durable log the sweep resumes from),
`manifest.json` (which suite it belongs to), `frames/` (strips of the first seed's
episodes), and, once the sweep is complete, `results.json`, `results.csv`, `report.md` and
the plots.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from ..language.grounding import DEFAULT_LEVEL, grounding_level
from ..policies import resolve_policy
from .backends import BACKENDS, Job, run_backend
from .episode import EpisodeKey, EpisodeRunner
from .layout import MANIFEST, RESULTS_LOG, frames_path
from .report import write_outputs
from .stats import ConditionSummary, summarize
from .store import ResultStore, atomic_write_bytes
from .suite import Suite, SuiteError

__all__ = ["run_sweep", "SweepResult", "plan_episodes"]


@dataclass
class SweepResult:
    """What a sweep produced."""

    out: Path
    records: list[dict]
    summaries: list[ConditionSummary]
    ran: int                       # episodes run by this call
    resumed: int                   # episodes found done in the log
    wall_s: float
    failed: int = field(init=False)

    def __post_init__(self) -> None:
        self.failed = sum(r["status"] != "ok" for r in self.records)


def plan_episodes(suite: Suite, policies: Sequence[str]) -> list[EpisodeKey]:
    """Every episode of the sweep, in report order: policy, condition (base first), seed."""
    return [EpisodeKey(p, c.name, s) for p in policies for c in suite.conditions for s in suite.seeds]


def _png(frames: np.ndarray) -> bytes:
    import imageio.v3 as iio

    return iio.imwrite("<bytes>", np.concatenate(list(frames), axis=1), extension=".png")


def _manifest_level(manifest: dict) -> str:
    """The grounding level a sweep's manifest records (older manifests: a `strict` flag)."""
    return manifest.get("grounding") or ("exact" if manifest.get("strict") else DEFAULT_LEVEL)


def _check_manifest(out: Path, suite: Suite, grounding: str) -> None:
    path = out / MANIFEST
    mine = {"suite": suite.name, "digest": suite.digest(), "env": suite.env_id, "grounding": grounding}
    if path.exists():
        try:
            theirs = json.loads(path.read_text())
        except json.JSONDecodeError:
            theirs = {}
        if theirs.get("digest") != mine["digest"]:
            raise SuiteError(f"{out} holds results of suite {theirs.get('suite')!r} with other settings (digest "
                             f"{theirs.get('digest')} vs {mine['digest']}); resume only the same suite, or use "
                             f"another --out")
        if _manifest_level(theirs) != grounding:
            raise SuiteError(f"{out} holds results of a sweep run with grounding {_manifest_level(theirs)!r} (this "
                             f"one: {grounding!r}); resume it with the same --grounding, or use another --out")
        return
    atomic_write_bytes(path, (json.dumps(mine, indent=2) + "\n").encode())


def _check_env(suite: Suite, cache_dir: Optional[str]) -> None:
    """Make the suite's env once here, so bad `env_kwargs` stop the sweep with one clear error."""
    try:
        EpisodeRunner(suite, cache_dir).env.close()
    except (TypeError, ValueError) as exc:
        raise SuiteError(f"Invalid env or env_kwargs in suite {suite.source}: {type(exc).__name__}: {exc}") from None


def run_sweep(suite: Suite, policies: Sequence[str], out: str | Path, backend: str = "local", workers: int = 1,
              cache_dir: Optional[str] = None, address: Optional[str] = None, progress: bool = True,
              report: bool = True, grounding: Optional[str] = None, strict: bool = False) -> SweepResult:
    """Run (or resume) a sweep of `suite` for each policy spec and write its outputs to `out`.
    `grounding`: the grounding level of the scene prompts (`language.grounding.LEVELS`; None: the
    one in force), recorded in the manifest and carried to every worker; under "exact" an episode
    whose scene prompt has a substituted word fails with the `CommandError`. `strict`: deprecated
    alias of ``grounding="exact"``."""
    if strict and grounding not in (None, "exact"):
        raise ValueError(f"Expected strict=True only with grounding None or 'exact', found {grounding!r}")
    grounding = grounding_level("exact" if strict else grounding)
    if backend not in BACKENDS:
        raise ValueError(f"Expected backend in {BACKENDS}, found {backend!r}")
    if not policies or len(set(policies)) != len(policies):
        raise ValueError(f"Expected one or more distinct policies, found {list(policies)!r}")
    for spec in policies:
        resolve_policy(spec)                            # an unknown policy stops the sweep before it starts
    _check_env(suite, cache_dir)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _check_manifest(out, suite, grounding)
    start = time.perf_counter()
    store = ResultStore(out / RESULTS_LOG)
    done = store.load()
    plan = plan_episodes(suite, policies)
    pending = [k for k in plan if k.id not in done]
    jobs: list[Job] = [(k, suite.frames if k.seed == suite.seed else 0) for k in pending]
    seeds = sorted({k.seed for k in pending})
    bar = _progress(len(plan), len(plan) - len(pending), suite.name, backend) if progress else None
    failed = sum(done[k.id]["status"] != "ok" for k in plan if k.id in done)
    with store:
        for res in run_backend(backend, suite, seeds, jobs, cache_dir, workers, address, grounding):
            key = EpisodeKey(res.record["policy"], res.record["perturbation"], res.record["seed"])
            if res.frames is not None:
                atomic_write_bytes(frames_path(out, key), _png(res.frames))
            record = dict(res.record, key=key.id)
            store.append(record)
            done[key.id] = record
            failed += record["status"] != "ok"
            if bar is not None:
                bar.set_postfix_str(f"failed {failed}", refresh=False)
                bar.update(1)
    if bar is not None:
        bar.close()
    records = [done[k.id] for k in plan]
    summaries = summarize(records, list(policies), [c.name for c in suite.conditions])
    result = SweepResult(out, records, summaries, len(pending), len(plan) - len(pending),
                         time.perf_counter() - start)
    if report:
        write_outputs(out, suite, list(policies), result.records, summaries,
                      {"backend": backend, "workers": workers, "wall_s": round(result.wall_s, 2), "ran": result.ran,
                       "resumed": result.resumed})
    return result


def _progress(total: int, initial: int, name: str, backend: str):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=f"{name} [{backend}]", unit="ep", dynamic_ncols=True)
