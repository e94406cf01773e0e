"""`apply_edit`: one language edit on a scene, with the env's policy for failed edits."""

from __future__ import annotations

from typing import Any, Mapping, Optional

import numpy as np

from morphosim_gym.errors import CommandError, EditError
from morphosim_gym.scene import Scene4D

__all__ = ["apply_edit", "view_camera_option", "view_change"]


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


def view_camera_option(before: Scene4D, after: Scene4D, camera: Mapping[str, Any],
                       default_fov: Optional[float]) -> dict[str, Any]:
    """The reset `camera` option once the reset edits have run: a field-of-view edit of the scene's
    generation camera ("widen the field of view") scales the task's start field of view by the same
    ratio (unless the option sets one). A moved generation camera needs nothing here: the tasks place
    the rig from the edited scene's camera."""
    out = dict(camera)
    ratio = after.camera.fov_y_deg / before.camera.fov_y_deg
    if "fov_y_deg" not in out and default_fov is not None and abs(ratio - 1.0) > 1e-9:
        out["fov_y_deg"] = float(min(max(default_fov * ratio, 1.0), 170.0))
    return out


def view_change(before: Scene4D, after: Scene4D) -> Optional[tuple[float, np.ndarray]]:
    """What an edit did to the scene's generation camera, as (field-of-view ratio, position shift [3]),
    or None when it left the camera as it was (every edit but the view edits)."""
    a, b = before.camera, after.camera
    if a is b:
        return None
    ratio = b.fov_y_deg / a.fov_y_deg
    shift = np.asarray(b.position, dtype=np.float64) - np.asarray(a.position, dtype=np.float64)
    if ratio == 1.0 and not np.any(shift):
        return None
    return ratio, shift
