"""`apply_edit`: one language edit on a scene, with the env's policy for failed edits."""

from __future__ import annotations

from typing import Any, Optional

from morphosim_gym.errors import CommandError, EditError
from morphosim_gym.scene import Scene4D

__all__ = ["apply_edit"]


def apply_edit(sim: Any, scene: Scene4D, text: str, policy: str) -> tuple[Scene4D, Optional[str]]:
    """(the edited scene, None), or with `policy="skip"` (the unedited scene, the error text) for an
    edit that fails; with `policy="raise"` the failure is raised as the same error type, its
    message naming the edit and the way to skip it."""
    edit = getattr(sim, "edit", None)
    if edit is None:
        raise NotImplementedError("Expected a MorphoSim with sim.edit(scene, text) (the scene editor), found "
                                  "none in this build")
    try:
        return edit(scene, text), None
    except (EditError, CommandError) as exc:
        if policy == "skip":
            return scene, f"{text}: {exc}"
        try:
            err = type(exc)(f"Edit {text!r} failed: {exc} (pass on_edit_error='skip' to go on without it)")
        except Exception:  # an error type with a different constructor: raise it as it is
            raise exc
        raise err from exc
