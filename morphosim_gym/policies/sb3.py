"""Saved Stable-Baselines3 policies as policy factories (`morphosim bench --policy ...`).

A model saved by `examples/train_ppo_track.py` is two files: `NAME.zip` (SB3's `model.save`) and
`NAME.json`, the settings its observations were made with (image size, rgb only, frame stack).
`sb3_policy(path)` rebuilds exactly those observations from the env's own: it keeps the `rgb`
image of the observation dict (as `RGBObservation` did in training) and stacks the last
`frame_stack` images along the channels, oldest first, with zero frames before the first (as
SB3's `VecFrameStack` does after a reset), then acts with `model.predict(deterministic=True)`.

    from morphosim_gym.policies.sb3 import sb3_policy
    factory = sb3_policy("examples/results/models/ppo_track_model.zip")

From the command line, name the model in an environment variable:

    MORPHOSIM_SB3_POLICY=path/to/ppo_track_model.zip \\
        morphosim bench axes_track --policy morphosim_gym.policies.sb3:policy_from_env

The env must render at the training size: a suite at another size fails at the first episode
with an error naming both sizes (set the suite's `env_kwargs: {width: .., height: ..}`).
Needs `stable-baselines3` (`pip install 'morphosim-gym[train]'`).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

import numpy as np

from .protocol import Act

__all__ = ["SB3Settings", "SB3Policy", "sb3_policy", "policy_from_env", "load_settings", "ENV_VAR", "SETTINGS_FORMAT"]

ENV_VAR = "MORPHOSIM_SB3_POLICY"
SETTINGS_FORMAT = "morphosim-sb3-policy/1"
OBSERVATIONS = ("rgb",)                     # what the settings' "observation" may name (the policy's input)
PADDINGS = ("zero",)                        # frame-stack padding before the first frame (SB3's VecFrameStack)


@dataclass(frozen=True)
class SB3Settings:
    """How a saved policy's observations were made (the `NAME.json` next to `NAME.zip`)."""

    algo: str
    width: int
    height: int
    frame_stack: int = 1
    observation: str = "rgb"
    frame_stack_padding: str = "zero"
    deterministic: bool = True
    env_id: Optional[str] = None


def _require(d: dict, key: str, kind: type, source: Path) -> Any:
    v = d.get(key)
    if isinstance(v, bool) and kind is not bool or not isinstance(v, kind):
        raise ValueError(f"Expected {key!r} as {kind.__name__} in the policy settings {source}, found {v!r}")
    return v


def load_settings(path: str | Path) -> SB3Settings:
    """The settings of a saved policy (`path` is the model's .zip or its .json); ValueError naming
    the file and the key for a missing file or a bad entry."""
    p = Path(path)
    source = p.with_suffix(".json")
    if not source.is_file():
        raise ValueError(f"Expected the policy settings {source} next to the model (written by "
                         f"examples/train_ppo_track.py), found no such file")
    try:
        d = json.loads(source.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"Expected JSON in the policy settings {source}, found: {exc}") from None
    if not isinstance(d, dict) or d.get("format") != SETTINGS_FORMAT:
        got = d.get("format") if isinstance(d, dict) else type(d).__name__
        raise ValueError(f"Expected policy settings of format {SETTINGS_FORMAT!r} in {source}, found {got!r}")
    s = SB3Settings(algo=_require(d, "algo", str, source), width=_require(d, "width", int, source),
                    height=_require(d, "height", int, source),
                    frame_stack=_require(d, "frame_stack", int, source),
                    observation=_require(d, "observation", str, source),
                    frame_stack_padding=d.get("frame_stack_padding", "zero"),
                    deterministic=bool(d.get("deterministic", True)), env_id=d.get("env_id"))
    if min(s.width, s.height, s.frame_stack) < 1:
        raise ValueError(f"Expected width, height and frame_stack >= 1 in {source}, found "
                         f"{s.width}, {s.height}, {s.frame_stack}")
    if s.observation not in OBSERVATIONS:
        raise ValueError(f"Expected 'observation' in {OBSERVATIONS} in {source}, found {s.observation!r}")
    if s.frame_stack_padding not in PADDINGS:
        raise ValueError(f"Expected 'frame_stack_padding' in {PADDINGS} in {source}, found {s.frame_stack_padding!r}")
    return s


def _sb3() -> Any:
    try:
        import stable_baselines3
    except ImportError as exc:
        raise ImportError("Expected stable-baselines3 for a saved SB3 policy, found it missing; "
                          "pip install 'morphosim-gym[train]'") from exc
    return stable_baselines3


_MODELS: dict[tuple[str, float], Any] = {}     # (resolved path, mtime) -> loaded model, one per process


def _load_model(path: Path, algo: str) -> Any:
    key = (str(path.resolve()), path.stat().st_mtime)
    if key not in _MODELS:
        sb3 = _sb3()
        cls = getattr(sb3, algo, None)
        if not isinstance(cls, type) or not hasattr(cls, "load"):
            raise ValueError(f"Expected 'algo' to name a stable_baselines3 algorithm (PPO, A2C, ...) in the settings "
                             f"of {path}, found {algo!r}")
        _MODELS[key] = cls.load(str(path), device="cpu")
    return _MODELS[key]


class _StackedAct:
    """One episode: the env's rgb image -> the stacked observation the model saw -> its action."""

    def __init__(self, model: Any, settings: SB3Settings, path: Path) -> None:
        self.model, self.s, self.path = model, settings, path
        self.stack: Optional[np.ndarray] = None

    def _image(self, obs: Any) -> np.ndarray:
        img = obs[self.s.observation] if isinstance(obs, dict) else obs
        img = np.asarray(img)
        want = (self.s.height, self.s.width, 3)
        if img.shape != want:
            raise ValueError(f"Expected {self.s.observation!r} images of shape {want} (the training settings of "
                             f"{self.path.name}), found {img.shape}; make the env with width={self.s.width}, "
                             f"height={self.s.height}")
        return img

    def __call__(self, obs: Any, info: dict) -> np.ndarray:
        img = self._image(obs)
        if self.stack is None:
            h, w, c = img.shape
            self.stack = np.zeros((h, w, c * self.s.frame_stack), dtype=img.dtype)
        c = img.shape[-1]
        self.stack[..., :-c] = self.stack[..., c:].copy()        # drop the oldest frame
        self.stack[..., -c:] = img
        action, _ = self.model.predict(self.stack, deterministic=self.s.deterministic)
        return np.asarray(action)


class SB3Policy:
    """A policy factory `factory(env, seed) -> act(obs, info)` of a saved SB3 model (loaded once per
    process, on the first episode). The seed is unused: actions are deterministic."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.__name__ = f"sb3:{self.path.name}"
        self._settings: Optional[SB3Settings] = None

    @property
    def settings(self) -> SB3Settings:
        """The model's observation settings (read on first use)."""
        if self._settings is None:
            self._settings = load_settings(self.path)
        return self._settings

    def __call__(self, env: Any, seed: int) -> Act:
        if not self.path.is_file():
            raise ValueError(f"Expected a saved SB3 model at {self.path}, found no such file")
        return _StackedAct(_load_model(self.path, self.settings.algo), self.settings, self.path)


def sb3_policy(path: str | Path) -> SB3Policy:
    """The policy factory of the SB3 model saved at `path` (.zip, with its .json settings beside it)."""
    return SB3Policy(path)


def policy_from_env(env: Any, seed: int) -> Act:
    """A factory for `--policy morphosim_gym.policies.sb3:policy_from_env`: the model named by the
    `MORPHOSIM_SB3_POLICY` environment variable."""
    path = os.environ.get(ENV_VAR, "").strip()
    if not path:
        raise ValueError(f"Expected the environment variable {ENV_VAR} to name a saved SB3 model (.zip), found it "
                         f"unset")
    return sb3_policy(path)(env, seed)
