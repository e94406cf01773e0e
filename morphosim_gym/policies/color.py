"""The `color` policy, one that sees: it finds the target in the image by the colour word of the instruction.

Unlike the oracle, it reads only what a camera policy could: the observation's RGB image, the
instruction in `info`, and the camera intrinsics in `info["cameras"]`. It is the built-in
example of a policy whose shortcut (colour = identity) the counterfactual suites expose:
recolour the target and it loses it; give a distractor the target's colour and it may follow
the distractor. Track (pan-tilt) and Find (free camera) are supported; other tasks raise.
"""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from morphosim_gym.colors import color_rgb, is_color_word
from morphosim_gym.metrics import rgb_to_lab

from .task import task_kind

__all__ = ["color_policy", "colour_mask", "instruction_color", "largest_blob"]

MATCH_DELTA_E = 28.0          # CIE76 distance from the named colour that still counts as it
MIN_PIXELS = 3


def instruction_color(instruction: str) -> Optional[np.ndarray]:
    """Lab of the first colour word of an instruction ("keep the red ball ..." -> red), or None."""
    for word in instruction.lower().replace(",", " ").split():
        if is_color_word(word):
            return rgb_to_lab(np.array(color_rgb(word), dtype=np.float64))
    return None


def colour_mask(rgb: np.ndarray, lab: np.ndarray) -> np.ndarray:
    """[H, W] pixels of an image within `MATCH_DELTA_E` of a Lab colour (lightness counts half, so
    shaded parts of an object still match)."""
    d = rgb_to_lab(rgb) - lab
    return np.sqrt((0.5 * d[..., 0]) ** 2 + d[..., 1] ** 2 + d[..., 2] ** 2) < MATCH_DELTA_E


def largest_blob(mask: np.ndarray) -> np.ndarray:
    """The largest 8-connected component of a mask (one object, not two of the same colour)."""
    import cv2

    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    if n <= 2:
        return mask
    return labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))


def _angles(mask: np.ndarray, k: np.ndarray) -> tuple[float, float, float]:
    """(horizontal angle right, vertical angle down, image fraction) of the mask's centroid."""
    rows, cols = np.nonzero(mask)
    u, v = cols.mean() + 0.5, rows.mean() + 0.5
    return (math.atan2(u - k[0, 2], k[0, 0]), math.atan2(v - k[1, 2], k[1, 1]), rows.size / mask.size)


class _ColorPolicy:
    def __init__(self, env: Any) -> None:
        self.env = env.unwrapped
        self.kind = task_kind(env, "the colour policy")
        if self.kind not in ("track", "find"):
            raise ValueError(f"Expected a Track or Find env for the colour policy, found task kind {self.kind!r}")
        self.dt = float(self.env.dt)
        self.lab: Optional[np.ndarray] = None

    def __call__(self, obs: dict, info: dict) -> np.ndarray:
        if self.lab is None:
            self.lab = instruction_color(str(info.get("instruction", "")))
        rig = self.env.rig
        mask = colour_mask(obs["rgb"], self.lab) if self.lab is not None else np.zeros(obs["rgb"].shape[:2], bool)
        mask = largest_blob(mask)
        k = np.asarray(info["cameras"]["eye"]["K"])
        seen = int(mask.sum()) >= MIN_PIXELS
        if self.kind == "track":
            action = np.zeros(3, dtype=np.float32)
            if seen:
                right, down, _ = _angles(mask, k)
                rates = np.array([-right, -down]) / self.dt / rig.max_rates[:2]
                action[:2] = np.clip(rates, -1.0, 1.0)
            return action
        action = np.zeros(6, dtype=np.float32)
        turn = rig.max_turn_rate * self.dt
        if not seen:
            action[3] = 0.6                                     # search: turn left on the spot
            return action
        right, down, area = _angles(mask, k)
        action[3] = np.clip(-right / turn, -1.0, 1.0)
        action[4] = np.clip(-down / turn, -1.0, 1.0)
        if math.hypot(right, down) < math.radians(15.0) and area < 0.03:
            action[1] = 1.0                                     # centred but small: fly closer
        return action


def color_policy(env: Any, seed: int) -> _ColorPolicy:
    """The colour-seeking policy for a Track or Find env (deterministic; the seed is unused)."""
    return _ColorPolicy(env)
