"""A fixed world for every episode: `scene=` a `Scene4D` or a scene file (`DIR/scene.msim`, e.g. from
`morphosim reconstruct VIDEO --out DIR`), checked when the env is made."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

from morphosim_gym.scene import Scene4D, load_scene

__all__ = ["FixedScene", "load_fixed_scene"]


@dataclass(frozen=True, eq=False)
class FixedScene:
    """The env's one scene and where it came from (a file path, or "<Scene4D>")."""

    scene: Scene4D
    origin: str

    @property
    def prompt(self) -> str:
        """What `info["prompt"]` shows: the scene's prompt, else its origin."""
        return self.scene.provenance.prompt or self.origin

    def resolve_target(self, task: Any, name: Optional[str]) -> Any:
        """The task's target in this scene; `ValueError` naming the scene and its objects if `name`
        is not one of them."""
        try:
            return task.resolve_target(self.scene, name)
        except ValueError as exc:
            names = [o.name for o in self.scene.objects if o.role != "background"]
            raise ValueError(f"Expected target {name!r} to be an object of the scene {self.origin}, found objects "
                             f"{names} ({exc})") from None


def check_scene_arg(name: str, value: Any) -> Any:
    """`scene=`: None, a `Scene4D` or a path (str / PathLike); "Expected ..., found ..." otherwise."""
    if value is None or isinstance(value, Scene4D):
        return value
    if isinstance(value, (str, os.PathLike)) and str(value).strip():
        return value
    raise ValueError(f"Expected {name} as a scene file path (.msim), a Scene4D or None, found {value!r}")


def load_fixed_scene(value: Any) -> Optional[FixedScene]:
    """The env's fixed scene from `scene=` (None: scenes come from prompts). A path that is not a
    readable scene file raises a `ValueError` naming it."""
    if value is None:
        return None
    if isinstance(value, Scene4D):
        return FixedScene(value, "<Scene4D>")
    path = Path(value)
    if not path.is_file():
        raise ValueError(f"Expected scene as a scene file (.msim), found no such file: {path}")
    try:
        scene = load_scene(path)
    except ValueError as exc:
        raise ValueError(f"Expected scene as a scene file (.msim, e.g. from `morphosim reconstruct`), found {path} "
                         f"is not one: {exc}") from None
    return FixedScene(scene, str(path))
