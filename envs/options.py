"""`ResetOptions`: the checked `options` of `env.reset(options=...)`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Optional

from morphosim_gym.tasks import check_camera_override

from .config import ON_EDIT_ERROR, check_int

__all__ = ["ResetOptions", "RESET_OPTION_KEYS"]

RESET_OPTION_KEYS = ("prompt", "scene_seed", "target", "edits", "camera", "on_edit_error")


@dataclass(frozen=True)
class ResetOptions:
    """One reset's options; None (or empty) where the option was not given.

    Attributes:
        prompt: generate this prompt instead of the env's scene choice.
        scene_seed: the generation seed.
        target: the target object's name.
        edits: language edits applied before the episode.
        camera: the rig's start view (checked by `check_camera_override`).
        on_edit_error: this episode's policy for failed edits ("raise" or "skip").
    """

    prompt: Optional[str] = None
    scene_seed: Optional[int] = None
    target: Optional[str] = None
    edits: tuple[str, ...] = ()
    camera: Mapping[str, Any] = field(default_factory=dict)
    on_edit_error: Optional[str] = None

    @classmethod
    def parse(cls, options: Optional[Mapping[str, Any]]) -> "ResetOptions":
        """Check a reset's `options` dict; "Expected ..., found ..." `ValueError` for bad values."""
        if options is None:
            return cls()
        if not isinstance(options, Mapping):
            raise ValueError(f"Expected options as a dict, found {type(options).__name__}")
        unknown = set(options) - set(RESET_OPTION_KEYS)
        if unknown:
            raise ValueError(f"Expected option keys in {list(RESET_OPTION_KEYS)}, found unknown {sorted(unknown)}")
        prompt, seed, target = options.get("prompt"), options.get("scene_seed"), options.get("target")
        if prompt is not None and (not isinstance(prompt, str) or not prompt.strip()):
            raise ValueError(f"Expected options['prompt'] as a non-empty string, found {prompt!r}")
        if seed is not None:
            seed = check_int(seed, "options['scene_seed']")
        if target is not None and not isinstance(target, str):
            raise ValueError(f"Expected options['target'] as an object name, found {target!r}")
        edits = _edits(options.get("edits", ()))
        camera = check_camera_override(options.get("camera"))
        policy = options.get("on_edit_error")
        if "on_edit_error" in options and policy not in ON_EDIT_ERROR:
            raise ValueError(f"Expected options['on_edit_error'] in {ON_EDIT_ERROR}, found {policy!r}")
        return cls(prompt, seed, target, edits, camera, policy)


def _edits(edits: Any) -> tuple[str, ...]:
    if isinstance(edits, str):
        edits = [edits]
    if edits is None:
        edits = ()
    if not isinstance(edits, (list, tuple)) or not all(isinstance(e, str) and e.strip() for e in edits):
        raise ValueError(f"Expected options['edits'] as a list of edit commands (strings), found {edits!r}")
    return tuple(edits)
