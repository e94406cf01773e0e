"""`AxisRandomization`: domain randomisation for training, over the perturbation axes.

    env = AxisRandomization(gym.make("MorphoSim/Track-v0"), "track")    # tasks/randomization/track.yaml
    obs, info = env.reset(seed=3)
    info["randomization"]     # {"axes": [...], "edits": [...], "camera": {...}, "params": {...}, "skipped": {...}}

At every reset the wrapper draws axes from the file's distributions (`tasks.randomization`), with a
generator seeded by the reset seed (the same seed gives the same draw; the env's own random stream
is untouched). The draw needs the episode's scene (the axes' templates name its target and
distractor), so the wrapper resets the env once to learn it and, if anything was drawn, once more
with the same seed, prompt, scene seed and target plus the drawn edits and camera shift (the scene
comes from the env's cache the second time). Axes that do not apply to the scene are listed under
`skipped` with the reason; edits that fail are skipped too and listed in `info["edit_errors"]`.
Held-out axes (the file's `held_out`) are never drawn: evaluate on them, e.g. with a suite
`axes: [...]` of those names. The sensor axes need `SensorEffects`; the wrapper adds it beneath
itself when the env has none.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any, Mapping, Optional

import gymnasium as gym
import numpy as np

from morphosim_gym.tasks.axes import template_values
from morphosim_gym.tasks.randomization import Randomization, load_randomization, sample_axes

from .sensor import SensorEffects

__all__ = ["AxisRandomization"]

_SALT = 0xA7E5


def _has_sensor(env: gym.Env) -> bool:
    while isinstance(env, gym.Wrapper):
        if isinstance(env, SensorEffects):
            return True
        env = env.env
    return False


class AxisRandomization(gym.Wrapper):
    """Sample perturbation axes per episode (see the module docstring).

    Args:
        env: a MorphoSim env (or a wrapper of one).
        config: a `Randomization`, a built-in name ("track"), a YAML path or a mapping.
    """

    def __init__(self, env: gym.Env, config: Randomization | str | Mapping[str, Any]) -> None:
        if not hasattr(env.unwrapped, "perturb"):
            raise ValueError(f"Expected a MorphoSim env (with perturb()), found {type(env.unwrapped).__name__}")
        super().__init__(env if _has_sensor(env) else SensorEffects(env))
        self.config = config if isinstance(config, Randomization) else load_randomization(config)
        self._rng = np.random.default_rng()

    @property
    def held_out(self) -> tuple[str, ...]:
        """The axes kept for evaluation (never drawn)."""
        return self.config.held_out

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[Any, dict]:
        if seed is not None:
            self._rng = np.random.default_rng([int(seed), _SALT])
        obs, info = self.env.reset(seed=seed, options=options)
        u = self.env.unwrapped
        request = SimpleNamespace(target=info["target"], target_description=None)
        draw = sample_axes(self.config, self._rng, template_values(u.scene, u.task, request))
        if draw.edits or draw.camera:
            opts = dict(options or {})
            given = opts.get("edits", ())
            given = [given] if isinstance(given, str) else list(given or ())
            opts.update(prompt=info["prompt"], scene_seed=info["scene_seed"], target=info["target"],
                        edits=given + list(draw.edits), on_edit_error="skip")
            if draw.camera:
                opts["camera"] = dict(opts.get("camera") or {}, **_camera(u.scene, draw.camera))
            obs, info = self.env.reset(seed=seed, options=opts)
        info["randomization"] = draw.to_info()
        return obs, info


def _camera(scene: Any, shift: Mapping[str, float]) -> dict[str, Any]:
    """The reset camera option of a camera shift: the generation camera orbited about the scene centre."""
    centre = scene.centre()
    cam = scene.camera.orbit(float(shift.get("orbit_deg", 0.0)), centre, float(shift.get("pitch_deg", 0.0)))
    return {"position": (centre + float(shift.get("distance_scale", 1.0)) * (cam.position - centre)).tolist()}
