"""Generate the MorphoSim paper's scenes from their prompts, apply the paper's edits, write videos.

    python examples/paper_scenes.py --out out/demo [--reconstruct] [--size 128]

For each prompt of the paper's figures this writes `NN_words_of_the_prompt.mp4`: the generation
view (left) and a 30-degree novel view (right), before (top) and after (bottom) the paper's edit of
that scene, each quarter labelled. With `--reconstruct` scenes are fitted from their clips (40-70 s
each at 128 px on a 2-core CPU) instead of taken from the generator's ground truth.
"""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

import cv2
import numpy as np

import morphosim_gym as ms
from morphosim_gym.generate.cli import write_video
from morphosim_gym.generate.examples import PAPER_SCENES


def labelled(image: np.ndarray, text: str) -> np.ndarray:
    """`image` with `text` written in its top-left corner (white on a dark outline)."""
    out = np.ascontiguousarray(image)
    scale = max(0.3, image.shape[0] / 400)
    for colour, width in (((0, 0, 0), 3), ((255, 255, 255), 1)):
        cv2.putText(out, text, (3, int(14 * scale / 0.35)), cv2.FONT_HERSHEY_SIMPLEX, scale, colour, width, cv2.LINE_AA)
    return out


def file_stem(k: int, prompt: str) -> str:
    """`NN_` and the prompt's first words, letters and digits only ("04_a_small_vibrant_fish")."""
    words = re.findall(r"[a-z0-9]+", prompt.lower())[:5]
    return f"{k:02d}_" + "_".join(words)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/demo")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--reconstruct", action="store_true", help="fit scenes from clips instead of the ground truth")
    args = ap.parse_args()
    out = Path(args.out)
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=args.size, height=args.size),
                       reconstruction="fit" if args.reconstruct else "oracle")
    for k, (prompt, edit) in enumerate(PAPER_SCENES):
        start = time.perf_counter()
        clip = sim.generate_clip(prompt, seed=0)
        scene = sim.reconstruct(clip)
        made = time.perf_counter() - start
        start = time.perf_counter()
        edited = sim.edit(scene, edit)
        edit_ms = 1000 * (time.perf_counter() - start)
        novel = scene.camera.orbit(30.0, scene.centre())
        frames = []
        for i in range(clip.num_frames):
            t = i / clip.fps
            after = labelled(ms.render(edited, edited.camera_at(t), t).rgb_uint8(), "after the edit")
            side = labelled(ms.render(edited, novel, t).rgb_uint8(), "after, novel 30 deg")
            top = np.concatenate([labelled(clip.frames[i], "generated"),
                                  labelled(ms.render(scene, novel, t).rgb_uint8(), "novel view 30 deg")], axis=1)
            frames.append(np.concatenate([top, np.concatenate([after, side], axis=1)], axis=0))
        path = write_video(frames, out / f"{file_stem(k, prompt)}.mp4", clip.fps)
        print(f"{path}: generated in {made:.1f} s, edit {edit!r} in {edit_ms:.1f} ms -> objects {edited.object_names}")


if __name__ == "__main__":
    main()
