"""Scene-quality report in the paper's table form: BRISQUE, NIQE, CLIP similarity, Q-Align.

    morphosim quality prompts.txt --out quality.md          # or: morphosim quality "a red ball ..." "..."

Each prompt's scene is generated (the generator's ground truth by default), rendered from the
generation view and from novel views (the generation camera orbited by each `yaws` offset
about the scene centre) at `times` instants over the clip, and every image is scored. BRISQUE
and NIQE run offline on every install; CLIP similarity and Q-Align need local models and are
marked unavailable otherwise. The table has the paper's columns and sections: the overall
average first, then one section per scene, one row per view group.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

__all__ = ["QualityConfig", "read_prompts", "score_prompts", "quality_markdown", "quality_main", "COLUMNS"]

COLUMNS = (("brisque", "BRISQUE ↓"), ("niqe", "NIQE ↓"), ("clip", "CLIP Similarity ↑"),
           ("qalign_quality", "QAlign Quality ↑"), ("qalign_aesthetic", "QAlign Aesthetic ↑"))


@dataclass(frozen=True)
class QualityConfig:
    """Settings of a quality report."""

    size: int = 384
    yaws: tuple[float, ...] = (-30.0, -15.0, 15.0, 30.0)
    times: int = 3
    seed: int = 0
    detail: float = 1.0
    reconstruction: str = "oracle"
    clip_model: Optional[str] = None
    qalign_model: Optional[str] = None
    trust_remote_code: bool = False       # let the Q-Align folder's own Python run (it needs it)
    assets: str = "auto"                  # GenerationConfig.assets: "auto", "off" (procedural) or "require"

    def __post_init__(self) -> None:
        if not 96 <= int(self.size) <= 2048:
            raise ValueError(f"Expected --size in [96, 2048] (NIQE needs 96x96 blocks), found {self.size}")
        if not 1 <= int(self.times) <= 100:
            raise ValueError(f"Expected --times in [1, 100], found {self.times}")
        if any(not math.isfinite(y) or y == 0.0 or abs(y) >= 180.0 for y in self.yaws):
            raise ValueError(f"Expected novel-view yaws non-zero and within (-180, 180) degrees, found {self.yaws}")


def read_prompts(items: Sequence[str]) -> list[str]:
    """Prompts from arguments: a readable file gives one prompt per non-empty line ('#' starts a
    comment line); anything else is a prompt."""
    out: list[str] = []
    for item in items:
        path = Path(item)
        if path.suffix in (".txt", ".prompts") or (len(item) < 256 and path.is_file()):
            if not path.is_file():
                raise ValueError(f"Expected a prompts file, found no file {item!r}")
            for line in path.read_text(encoding="utf-8").splitlines():
                line = line.strip()
                if line and not line.startswith("#"):
                    out.append(line)
        elif item.strip():
            out.append(item.strip())
    if not out:
        raise ValueError(f"Expected at least one prompt, found none in {list(items)!r}")
    return out


def _group(yaw: float) -> str:
    return "generation view" if yaw == 0 else f"novel views (±{abs(yaw):g}°)"


def _views(scene: Any, cfg: QualityConfig) -> list[tuple[float, float, Any]]:
    """(yaw, t, camera) of every image to score."""
    out = []
    for t in np.linspace(0.0, scene.duration, cfg.times):
        base = scene.camera_at(float(t))
        h = max(8, int(round(cfg.size * base.height / base.width)))
        base = base.resized(cfg.size, h)
        centre = scene.centre(float(t))
        for yaw in (0.0,) + tuple(cfg.yaws):
            out.append((yaw, float(t), base if yaw == 0 else base.orbit(yaw, centre)))
    return out


def score_prompts(prompts: Sequence[str], cfg: QualityConfig, progress: bool = True) -> dict:
    """Generate, render and score every prompt; a JSON-friendly dict with every image's scores."""
    from morphosim_gym.generate.compose import GenerationConfig
    from morphosim_gym.metrics.brisque_score import BrisqueScorer
    from morphosim_gym.metrics.niqe import niqe
    from morphosim_gym.pipeline import MorphoSim
    from morphosim_gym.render import render

    from .semantic import load_clip, load_qalign

    sim = MorphoSim(reconstruction=cfg.reconstruction, generation=GenerationConfig(detail=cfg.detail, assets=cfg.assets))
    brisque = BrisqueScorer()
    clip, clip_why = load_clip(cfg.clip_model)
    qalign, qalign_why = load_qalign(cfg.qalign_model, trust_remote_code=cfg.trust_remote_code)
    images: list[dict] = []
    start = time.perf_counter()
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(prompts), desc="quality", unit="scene", dynamic_ncols=True)
    for prompt in prompts:
        scene = sim.generate(prompt, seed=cfg.seed)
        shots = []
        for yaw, t, cam in _views(scene, cfg):
            rgb = render(scene, cam, t).rgb_uint8()
            row: dict[str, Any] = {"prompt": prompt, "group": _group(yaw), "yaw": yaw, "t": round(t, 4),
                                   "brisque": brisque(rgb), "niqe": niqe(rgb)}
            if clip is not None:
                row["clip"] = clip(rgb, prompt)
            images.append(row)
            shots.append(rgb)
        if qalign is not None:
            mine = images[-len(shots):]
            for task in ("quality", "aesthetic"):
                for row, s in zip(mine, qalign(shots, task)):
                    row[f"qalign_{task}"] = s
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    unavailable = {"clip": clip_why, "qalign_quality": qalign_why, "qalign_aesthetic": qalign_why}
    return {"config": asdict(cfg), "prompts": list(prompts), "images": images,
            "unavailable": {k: v for k, v in unavailable.items() if v}, "wall_s": round(time.perf_counter() - start, 2)}


def _cell(rows: list[dict], key: str, unavailable: dict) -> str:
    if key in unavailable:
        return "unavailable"
    vals = [r[key] for r in rows if key in r and r[key] is not None and math.isfinite(r[key])]
    return f"{np.mean(vals):.3f}" if vals else "n/a"


def _section(title: str, rows: list[dict], groups: list[str], unavailable: dict) -> list[str]:
    out = [f"| ***{title}*** | | | | | |"]
    for g in groups:
        mine = [r for r in rows if r["group"] == g]
        out.append(f"| {g} | " + " | ".join(_cell(mine, k, unavailable) for k, _ in COLUMNS) + " |")
    return out


def quality_markdown(data: dict) -> str:
    """The report: the paper's table (overall average, then one section per scene) and notes."""
    cfg, images, unavailable = data["config"], data["images"], data["unavailable"]
    groups = [_group(0.0)] + sorted({_group(y) for y in cfg["yaws"]}, key=lambda g: float(g.split("±")[1][:-2]))
    lines = ["# Scene quality (no-reference metrics)", "",
             f"{len(data['prompts'])} scenes (seed {cfg['seed']}, detail {cfg['detail']}, reconstruction "
             f"`{cfg['reconstruction']}`), each rendered at {cfg['size']} px from the generation view and from novel "
             f"views orbited by {', '.join(f'{y:+g}°' for y in cfg['yaws'])} about the scene centre, at "
             f"{cfg['times']} instants over the clip; every cell is the mean over those images.", "",
             "| View | " + " | ".join(name for _, name in COLUMNS) + " |",
             "|---|" + "---:|" * len(COLUMNS)]
    lines += _section("Overall average", images, groups, unavailable)
    for prompt in data["prompts"]:
        lines += _section(f"Scene: {prompt}", [r for r in images if r["prompt"] == prompt], groups, unavailable)
    lines += ["", "BRISQUE: the `brisque` package's LIVE-trained SVM (lower is better). NIQE: our implementation with "
              "the published pristine model (lower is better). Both were fitted to natural photographs: smooth "
              "synthetic renders with large flat areas (a clear sky) read as less natural to them than textured ones."]
    for key, why in unavailable.items():
        lines.append(f"- {dict(COLUMNS)[key]}: unavailable ({why})")
    lines += ["", f"Scoring took {data['wall_s']} s."]
    return "\n".join(lines) + "\n"


def quality_main(args: argparse.Namespace) -> int:
    """`morphosim quality`: write the report and its JSON; exit 0."""
    try:
        yaws = tuple(float(y) for y in str(args.yaws).split(",") if y.strip())
    except ValueError:
        raise ValueError(f"Expected --yaws as comma-separated degrees, found {args.yaws!r}") from None
    cfg = QualityConfig(size=args.size, yaws=yaws, times=args.times, seed=args.seed, detail=args.detail,
                        reconstruction=args.reconstruction, clip_model=args.clip_model, qalign_model=args.qalign_model,
                        trust_remote_code=bool(getattr(args, "trust_remote_code", False)))
    data = score_prompts(read_prompts(args.prompts), cfg)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(quality_markdown(data), encoding="utf-8")
    out.with_suffix(".json").write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    print(f"quality: {len(data['prompts'])} scenes, {len(data['images'])} images -> {out}")
    return 0
