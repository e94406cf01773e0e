"""`morphosim generate`, `morphosim render` and `morphosim edit`: scenes from the command line."""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from ..language.grounding_cli import add_grounding_flags, grounding_from_args

__all__ = ["register", "write_video"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the generation, rendering and editing subcommands."""
    p = sub.add_parser("generate", help="generate a 4D scene from a sentence: video, scene file, clip, summary")
    p.add_argument("prompt")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--size", type=int, default=None,
                   help="frame width and height in pixels (default 128; diffusion: its config's, 720x480)")
    p.add_argument("--frames", type=int, default=None, help="clip frames (default 49, or the diffusion config's)")
    p.add_argument("--fps", type=float, default=None, help="frame rate (default 8, or the diffusion config's)")
    p.add_argument("--format", choices=["mp4", "gif"], default="mp4")
    add_grounding_flags(p)
    p.add_argument("--reconstruct", action="store_true",
                   help="write the scene reconstructed from the clip (about two minutes) instead of the "
                        "generator's ground truth (a generator without one, e.g. diffusion, writes no scene "
                        "without this flag)")
    p.add_argument("--generator", default="procedural",
                   help="clip generator: procedural (default), diffusion (local CogVideoX weights, see "
                        "--weights), or module:factory (imports and runs that module)")
    p.add_argument("--weights", default=None,
                   help="diffusion: local directory of a diffusers CogVideoX pipeline (never downloaded)")
    p.add_argument("--diffusion-config", default=None,
                   help="diffusion: a YAML file of DiffusionConfig keys (device, num_inference_steps, guidance...)")
    p.add_argument("--steps", type=int, default=None, help="diffusion: denoising steps (num_inference_steps)")
    _parser_option(p)
    p.set_defaults(func=_generate)

    p = sub.add_parser("render", help="render a scene file to a video (optionally orbiting it)")
    p.add_argument("scene")
    p.add_argument("--out", required=True, help="video path (.mp4 or .gif)")
    p.add_argument("--orbit", action="store_true", help="orbit the camera around the scene centre")
    p.add_argument("--degrees", type=float, default=360.0, help="orbit sweep in degrees")
    p.add_argument("--size", type=int, default=None, help="render size (default: the scene camera's)")
    p.add_argument("--frames", type=int, default=None, help="number of video frames (default: the clip's)")
    p.add_argument("--fps", type=float, default=None)
    p.set_defaults(func=_render)

    p = sub.add_parser("edit", help="edit a scene by language and write it with a before/after video")
    p.add_argument("scene")
    p.add_argument("text")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--novel-yaw", type=float, default=30.0, help="yaw of the novel view, degrees")
    _parser_option(p)
    p.set_defaults(func=_edit)


def _parser_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--parser", default="rules",
                   help="command parser: rules (offline default), llm (the MORPHOSIM_LLM_* environment), auto, "
                        "or module:factory")


def _diffusion_config(args: argparse.Namespace) -> object:
    """The `DiffusionConfig` of the generate flags (a YAML file, then --weights, --size, --frames,
    --fps and --steps over it)."""
    from ..config_yaml import load_yaml_file
    from .diffusion.backend import DiffusionConfig

    data = load_yaml_file(args.diffusion_config) if args.diffusion_config else {}
    if not isinstance(data, dict):
        raise ValueError(f"Expected a mapping of diffusion keys in {args.diffusion_config}, found "
                         f"{type(data).__name__}")
    data = dict(data.get("diffusion", data))
    flags = {"weights_path": args.weights, "height": args.size, "width": args.size, "num_frames": args.frames,
             "fps": args.fps, "num_inference_steps": args.steps}
    data.update({k: v for k, v in flags.items() if v is not None})
    return DiffusionConfig.from_dict(data)


def _sim_config(args: argparse.Namespace) -> object:
    """The `SimConfig` of the generate flags."""
    from ..pipeline import SimConfig
    from .compose import GenerationConfig

    defaults = GenerationConfig()
    size = {"width": args.size, "height": args.size, "num_frames": args.frames, "fps": args.fps}
    generation = GenerationConfig(**{k: getattr(defaults, k) if v is None else v for k, v in size.items()})
    diffusion = _diffusion_config(args) if args.generator == "diffusion" else None
    given = [flag for flag, v in (("--weights", args.weights), ("--diffusion-config", args.diffusion_config),
                                  ("--steps", args.steps)) if v is not None]
    if diffusion is None and given:
        raise ValueError(f"Expected {', '.join(given)} only with --generator diffusion, found --generator "
                         f"{args.generator}")
    # a generator other than the procedural one may have no ground truth: fit when asked, else keep its clip
    reconstruction = "oracle" if args.generator == "procedural" and not args.reconstruct else "fit"
    return SimConfig(generator=args.generator, generation=generation, reconstruction=reconstruction,
                     diffusion=diffusion, parser=args.parser,
                     grounding=grounding_from_args(args))


def write_video(frames: list[np.ndarray], path: Path, fps: float) -> Path:
    """Write uint8 frames as mp4 or gif (by extension), atomically."""
    import imageio.v2 as imageio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = path.suffix.lower()
    if suffix not in (".mp4", ".gif"):
        raise ValueError(f"Expected a video path ending in .mp4 or .gif, found {path.name!r}")
    with tempfile.TemporaryDirectory(dir=path.parent) as tmp:
        tmp_path = Path(tmp) / f"video{suffix}"
        if suffix == ".gif":
            imageio.mimsave(tmp_path, frames, duration=1000.0 / fps, loop=0)
        else:
            imageio.mimsave(tmp_path, frames, fps=fps, macro_block_size=1)
        shutil.move(str(tmp_path), path)
    return path


def _generate(args: argparse.Namespace) -> int:
    from ..pipeline import MorphoSim
    from ..scene import save_clip, save_scene

    out = Path(args.out)
    sim = MorphoSim(_sim_config(args))
    start = time.perf_counter()
    plan = sim.parse(args.prompt)               # errors before anything is written
    clip = sim.generate_clip(args.prompt, seed=args.seed)
    scene = _scene_of(sim, clip, plan, args.reconstruct)
    seconds = time.perf_counter() - start
    summary = _summary(args, sim, plan, clip, scene, seconds)
    with tempfile.TemporaryDirectory(prefix=".generate-", dir=out.parent if out.parent.exists() else None) as tmp:
        stage = Path(tmp)
        write_video(list(clip.frames), stage / f"clip.{args.format}", clip.fps)
        if scene is not None:
            save_scene(scene, stage / "scene.msim")
        save_clip(clip, stage / "clip.mclip")
        (stage / "summary.json").write_text(json.dumps(summary, indent=2))
        out.mkdir(parents=True, exist_ok=True)
        for f in stage.iterdir():
            shutil.move(str(f), out / f.name)
    print(json.dumps({k: summary[k] for k in ("prompt", "seed", "seconds", "setting", "edits")}))
    if scene is None:
        skipped = f" (follow-up edits {[f.text for f in plan.then]} need a scene)" if plan.then else ""
        print(f"wrote {out}/clip.{args.format}, clip.mclip, summary.json; no scene.msim: the {sim.config.generator} "
              f"clip has no ground truth, pass --reconstruct to fit one{skipped}")
    else:
        print(f"wrote {out}/clip.{args.format}, scene.msim, clip.mclip, summary.json")
    return 0


def _scene_of(sim: object, clip: object, plan: object, reconstruct: bool) -> object:
    """The scene `morphosim generate` writes: fitted (--reconstruct), the generator's ground truth, or
    None for a clip without one; follow-up edits applied."""
    if reconstruct or sim.config.reconstruction == "oracle":
        scene = sim.reconstruct(clip)
    elif clip.ground_truth is not None:
        scene = clip.ground_truth
    else:
        return None
    return sim.apply_follow_ups(scene, plan)


def _summary(args: argparse.Namespace, sim: object, plan: object, clip: object, scene: object,
             seconds: float) -> dict:
    """summary.json of `morphosim generate` (objects from the clip's labels when there is no scene)."""
    objects = [{"id": int(i), "name": name} for i, name in sorted(clip.labels.items())] if scene is None \
        else [o.to_dict() for o in scene.objects]
    summary = {"prompt": args.prompt, "seed": args.seed, "seconds": round(seconds, 3),
               "generator": sim.config.generator, "parser": sim.config.parser,
               "frames": clip.num_frames, "size": [clip.width, clip.height], "fps": clip.fps,
               "objects": objects, "setting": clip.info.get("setting"),
               "edits": [] if scene is None else list(scene.history), "plan": plan.to_dict(),
               "scene_id": None if scene is None else scene.content_hash(),
               "trajectories": clip.info.get("trajectories", {})}
    guidance = clip.info.get("guidance")
    if guidance:
        summary["guidance_energy"] = guidance.get("energy")
    return summary


def _render(args: argparse.Namespace) -> int:
    from ..render import render
    from ..scene import load_scene

    scene = load_scene(args.scene)
    n = args.frames or scene.num_frames
    fps = args.fps or scene.fps
    frames = []
    centre = scene.centre()
    for i in range(n):
        t = scene.duration * i / max(n - 1, 1)
        cam = scene.camera_at(t)
        if args.size:
            cam = cam.resized(args.size, args.size)
        if args.orbit:
            cam = cam.orbit(args.degrees * i / max(n, 1), centre)
        frames.append(render(scene, cam, t).rgb_uint8())
    path = write_video(frames, Path(args.out), fps)
    print(f"wrote {path} ({n} frames)")
    return 0


def _edit(args: argparse.Namespace) -> int:
    from ..pipeline import MorphoSim
    from ..render import render
    from ..scene import load_scene, save_scene

    scene = load_scene(args.scene)
    sim = MorphoSim(parser=args.parser)
    start = time.perf_counter()
    edited = sim.edit(scene, args.text)
    seconds = time.perf_counter() - start
    out = Path(args.out)
    novel = scene.camera.orbit(args.novel_yaw, scene.centre())
    frames = []
    for i in range(scene.num_frames):
        t = i / scene.fps
        views = [render(s, c, t).rgb_uint8() for c in (scene.camera_at(t), novel) for s in (scene, edited)]
        top = np.concatenate(views[:2], axis=1)
        bottom = np.concatenate(views[2:], axis=1)
        frames.append(np.concatenate([top, bottom], axis=0))
    out.mkdir(parents=True, exist_ok=True)
    save_scene(edited, out / "edited.msim")
    write_video(frames, out / "before_after.mp4", scene.fps)
    print(json.dumps({"edit": args.text, "seconds": round(seconds, 4), "objects": edited.object_names,
                      "history": list(edited.history)}))
    print(f"wrote {out}/edited.msim and before_after.mp4 (top: generation view, bottom: {args.novel_yaw:g} deg "
          f"novel view; left: before, right: after)")
    return 0
