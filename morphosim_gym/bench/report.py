"""A finished sweep's outputs: results.json, results.csv, report.md and its plots."""

from __future__ import annotations

import csv
import io
import json
from dataclasses import asdict
from pathlib import Path
from typing import Any, Optional

from .stats import ConditionSummary, Interval, PowerSummary, power
from .store import atomic_write_bytes
from .suite import BASE, Suite

__all__ = ["write_outputs", "CSV_COLUMNS", "TIMING_FIELDS"]

CSV_COLUMNS = ("key", "policy", "perturbation", "seed", "status", "success", "return", "steps", "terminated",
               "perturbed", "prompt", "scene_seed", "target", "edits", "at", "camera", "error_stage", "error", "wall_s")
TIMING_FIELDS = ("wall_s",)        # the only record fields that differ between identical runs
MAX_ERRORS_LISTED = 30


def _suite_dict(suite: Suite) -> dict:
    return {"name": suite.name, "env": suite.env_id, "source": suite.source, "digest": suite.digest(),
            "description": suite.description, "task": suite.task.name, "scene_prompt": suite.task.scenes.prompt,
            "seed": suite.seed, "episodes": suite.episodes, "env_kwargs": dict(suite.env_kwargs),
            "perturbations": [asdict(p) for p in suite.perturbations]}


def _csv(records: list[dict]) -> bytes:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=CSV_COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in records:
        row = dict(r, edits=" | ".join(r.get("edits") or []),
                   camera=json.dumps(r["camera"], sort_keys=True) if r.get("camera") else "")
        w.writerow(row)
    return buf.getvalue().encode()


def _fmt(iv: Optional[Interval], digits: int = 2, signed: bool = False, percent: bool = False) -> str:
    if iv is None:
        return "—"
    if iv.n == 0:
        return "n/a"
    scale = 100.0 if percent else 1.0
    sign = "+" if signed else ""
    unit = "%" if percent else ""
    return (f"{iv.mean * scale:{sign}.{digits}f}{unit} [{iv.low * scale:{sign}.{digits}f}, "
            f"{iv.high * scale:{sign}.{digits}f}]")


def _condition_rows(suite: Suite) -> list[str]:
    rows = ["| condition | edits | when | camera |", "|---|---|---|---|", f"| {BASE} | — | — | — |"]
    for p in suite.perturbations:
        if p.error:
            rows.append(f"| {p.name} | **invalid:** {p.error} | | |")
            continue
        edits = "; ".join(f"`{e}`" for e in p.edits) or "—"
        when = "reset" if p.at == 0 else f"before step {p.at}"
        cam = ", ".join(f"{k}={v}" for k, v in asdict(p.camera).items() if v not in (None, 0.0, 1.0)) \
            if p.camera else "—"
        rows.append(f"| {p.name} | {edits} | {when} | {cam} |")
    return rows


def _results_rows(summaries: list[ConditionSummary]) -> list[str]:
    rows = ["| condition | episodes | failed | success rate [95% CI] | mean return [95% CI] | "
            "Δ success vs base [95% CI] | Δ return vs base [95% CI] |",
            "|---|---:|---:|---|---|---|---|"]
    for s in summaries:
        rows.append(f"| {s.perturbation} | {s.episodes} | {s.failed} | {_fmt(s.success, 0, percent=True)} | "
                    f"{_fmt(s.returns)} | {_fmt(s.delta_success, 0, True, True)} | {_fmt(s.delta_return, 2, True)} |")
    return rows


def _num(v: float, digits: int = 3) -> str:
    if v != v:            # nan
        return "n/a"
    return "∞" if v == float("inf") else f"{v:.{digits}g}"


def _power_rows(rows: list[PowerSummary]) -> list[str]:
    out = ["| condition | metric | pairs | paired 95% CI width | unpaired 95% CI width | unpaired episodes needed "
           "per paired one | episodes pairing saves |", "|---|---|---:|---:|---:|---:|---:|"]
    for p in rows:
        saved = "n/a" if p.saved != p.saved else f"{100 * p.saved:.0f}%"
        ratio = _num(p.episode_ratio)
        out.append(f"| {p.perturbation} | {p.metric} | {p.pairs} | {_num(p.paired_width)} | "
                   f"{_num(p.unpaired_width)} | {ratio if ratio == 'n/a' else ratio + '×'} | {saved} |")
    return out


def _power_section(power_rows: list[PowerSummary], policies: list[str]) -> list[str]:
    lines = ["", "## Statistical power: paired vs unpaired design", "",
             "The same episodes analysed two ways: paired (each perturbed episode against the base episode of its "
             "seed, the suite's design) and unpaired (the two groups resampled independently, as if the seeds "
             "differed). Interval widths shrink as 1/√n, so an unpaired design needs (unpaired / paired width)² "
             "times the episodes for the paired width; 'saves' is 1 − (paired / unpaired)². ∞: the paired "
             "differences do not vary at all; n/a: neither design sees any variation."]
    for policy in policies:
        lines += ["", f"Policy `{policy}`:", ""]
        lines += _power_rows([p for p in power_rows if p.policy == policy])
    return lines


def _markdown(suite: Suite, policies: list[str], records: list[dict], summaries: list[ConditionSummary],
              run: dict, figures: dict[str, str], power_rows: list[PowerSummary]) -> str:
    lines = [f"# Counterfactual robustness: suite `{suite.name}` ({suite.env_id})", ""]
    if suite.description:
        lines += [suite.description.strip(), ""]
    lines += [f"- scenes: `{suite.task.scenes.prompt}` (task `{suite.task.name}`), seeds {suite.seed}.."
              f"{suite.seed + suite.episodes - 1} ({suite.episodes} per condition)",
              f"- policies: {', '.join(f'`{p}`' for p in policies)}",
              "- every perturbed episode runs on the same scene, reset seed and policy seed as the base episode "
              "of its seed; Δ is perturbed minus base over those pairs, with a percentile-bootstrap 95% interval",
              f"- run: backend `{run.get('backend')}`, {run.get('workers')} worker(s), {run.get('ran')} episodes run "
              f"and {run.get('resumed')} resumed in {run.get('wall_s')} s "
              f"(suite digest `{suite.digest()}`)", "", "## Conditions", ""]
    lines += _condition_rows(suite)
    for policy in policies:
        lines += ["", f"## Policy `{policy}`", ""]
        lines += _results_rows([s for s in summaries if s.policy == policy])
    lines += _power_section(power_rows, policies)
    if figures:
        lines += ["", "## Plots", ""]
        for title, name in figures.items():
            lines += [f"**{title}**", "", f"![{title}]({name})", ""]
    failed = [r for r in records if r["status"] != "ok"]
    lines += ["", f"## Failed episodes ({len(failed)})", ""]
    if failed:
        lines += ["| episode | stage | error |", "|---|---|---|"]
        for r in failed[:MAX_ERRORS_LISTED]:
            text = str(r["error"]).replace("|", "\\|").replace("\n", " ")
            lines.append(f"| `{r['key']}` | {r['error_stage']} | {text} |")
        if len(failed) > MAX_ERRORS_LISTED:
            lines.append(f"| ... | | {len(failed) - MAX_ERRORS_LISTED} more in results.csv |")
    else:
        lines.append("None.")
    return "\n".join(lines) + "\n"


def write_outputs(out: Path, suite: Suite, policies: list[str], records: list[dict],
                  summaries: list[ConditionSummary], run: dict[str, Any]) -> None:
    """Write results.json, results.csv, the plots and report.md into `out`."""
    from .plots import bar_chart, frame_strips, power_chart

    power_rows = power(records, policies, [c.name for c in suite.conditions])
    data = {"suite": _suite_dict(suite), "policies": policies, "run": run,
            "summary": [s.as_dict() for s in summaries], "power": [p.as_dict() for p in power_rows],
            "episodes": records}
    atomic_write_bytes(out / "results.json", (json.dumps(data, indent=1, sort_keys=True) + "\n").encode())
    atomic_write_bytes(out / "results.csv", _csv(records))
    figures: dict[str, str] = {}
    conditions = [c.name for c in suite.conditions]
    if bar_chart(out / "success.png", summaries, policies, conditions):
        figures["Success rate and paired difference to the base (95% bootstrap intervals)"] = "success.png"
    if power_chart(out / "power.png", power_rows):
        figures["Statistical power: paired against unpaired interval widths on the same episodes"] = "power.png"
    for policy in policies:
        name = frame_strips(out, suite, policy)
        if name:
            figures[f"Frames of seed {suite.seed}, policy `{policy}`: base and each perturbation"] = name
    atomic_write_bytes(out / "report.md", _markdown(suite, policies, records, summaries, run, figures, power_rows).encode())
