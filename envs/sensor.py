"""`SensorEffects`: an observation wrapper that degrades the camera images (noise, blur, JPEG).

The effects are the wrapper's own (`SensorEffects(env, noise=0.3)`) plus those the current scene
carries (`scene.sensor`, set by language edits such as "add sensor noise" or "blur the images"),
so a sensor perturbation is a language edit like every other axis, at reset or mid-episode.
Each effect has a strength in (0, 1]; the pipeline is the camera's: blur (optics), then noise
(the sensor), then JPEG (the encoder). Noise is drawn from the wrapper's generator, seeded by the
reset seed, so rollouts stay reproducible. Without any effect the observation passes through
untouched (the same object).
"""

from __future__ import annotations

from typing import Any, Mapping, Optional

import cv2
import gymnasium as gym
import numpy as np

__all__ = ["SensorEffects", "apply_sensor", "SENSOR_ORDER"]

SENSOR_ORDER = ("blur", "noise", "jpeg")


def _blur(img: np.ndarray, amount: float, rng: np.random.Generator) -> np.ndarray:
    sigma = 0.3 + 2.7 * amount * img.shape[0] / 64.0          # about 3 px at full strength on a 64 px image
    return cv2.GaussianBlur(img, (0, 0), sigmaX=sigma)


def _noise(img: np.ndarray, amount: float, rng: np.random.Generator) -> np.ndarray:
    noisy = img.astype(np.float32) + rng.normal(0.0, 40.0 * amount, img.shape).astype(np.float32)
    return np.clip(noisy + 0.5, 0, 255).astype(np.uint8)


def _jpeg(img: np.ndarray, amount: float, rng: np.random.Generator) -> np.ndarray:
    quality = int(round(95 - 90 * amount))                    # 95 (light) .. 5 (blocky)
    ok, buf = cv2.imencode(".jpg", np.ascontiguousarray(img[..., ::-1]), [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise RuntimeError("Expected OpenCV to encode a JPEG, found a failure")
    return np.ascontiguousarray(cv2.imdecode(buf, cv2.IMREAD_COLOR)[..., ::-1])


_EFFECTS = {"blur": _blur, "noise": _noise, "jpeg": _jpeg}


def apply_sensor(img: np.ndarray, effects: Mapping[str, float], rng: np.random.Generator) -> np.ndarray:
    """The uint8 image [H, W, 3] through the effects (name -> strength), in `SENSOR_ORDER`."""
    out = img
    for name in SENSOR_ORDER:
        if name in effects:
            out = _EFFECTS[name](out, float(effects[name]), rng)
    return out


class SensorEffects(gym.ObservationWrapper):
    """Degrade every `rgb*` image of the observation (see the module docstring).

    Args:
        env: a MorphoSim env (or a wrapper of one).
        noise, blur, jpeg: fixed strengths in [0, 1] (0: off) applied on top of the scene's effects
            (a scene effect of the same name wins).
    """

    def __init__(self, env: gym.Env, noise: float = 0.0, blur: float = 0.0, jpeg: float = 0.0) -> None:
        super().__init__(env)
        self._fixed = {}
        for name, v in (("noise", noise), ("blur", blur), ("jpeg", jpeg)):
            v = float(v)
            if not (np.isfinite(v) and 0.0 <= v <= 1.0):
                raise ValueError(f"Expected {name} strength in [0, 1], found {v!r}")
            if v > 0:
                self._fixed[name] = v
        self._rng = np.random.default_rng()

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[Any, dict]:
        if seed is not None:
            self._rng = np.random.default_rng([int(seed), 0x5E45])
        return super().reset(seed=seed, options=options)

    def effects(self) -> dict[str, float]:
        """The effects now: the wrapper's, then the current scene's."""
        scene = getattr(self.env.unwrapped, "_world", None)
        found = dict(self._fixed)
        if scene is not None:
            found.update(dict(scene.scene.sensor))
        return found

    def observation(self, observation: Any) -> Any:
        effects = self.effects()
        if not effects or not isinstance(observation, Mapping):
            return observation
        out = dict(observation)
        for key, value in observation.items():
            if key.startswith("rgb") and isinstance(value, np.ndarray) and value.dtype == np.uint8:
                out[key] = apply_sensor(value, effects, self._rng)
        return out
