"""`SceneEditor`: language edits applied directly to a `Scene4D` (no re-generation).

    editor = SceneEditor()
    blue = editor.edit(scene, "make the ball blue")      # a new scene; `scene` is untouched
    blue.undo() is scene                                 # True: the edit history is a parent chain

A command is parsed against the scene (targets resolved by meaning; `EditError` when nothing
matches, or when a target is ambiguous), each operation selects its Gaussians (see
`select.py`) and is applied in order (see `ops.py`); the whole command is one step of the
scene's history.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..errors import CommandError, EditError
from ..language.backends import Parser, RulesParser
from ..language.plan import CameraOp, EditOp, ExtractOp, RecolorOp, RedirectOp, RemoveOp, ReverseOp, SpeedOp, StopOp
from ..scene import Provenance, Scene4D
from ..scene.camera import camera_path
from . import ops
from .axis_handlers import AXIS_HANDLERS
from .select import Selection, Selector

__all__ = ["SceneEditor"]


class SceneEditor:
    """Applies edit commands to scenes.

    Args:
        selector: how targets become Gaussian selections (default `Selector()`; its cache is
            what makes repeated edits of one target fast).
        parser: what turns the edit text into a plan (a `language.backends.Parser`; default the
            rule parser). `MorphoSim` passes the one `SimConfig.parser` names.
    """

    def __init__(self, selector: Selector | None = None, parser: Parser | None = None) -> None:
        self.selector = selector or Selector()
        if parser is not None and not isinstance(parser, Parser):
            raise ValueError(f"Expected parser with a parse(text, scene, require_scene=...) method, found "
                             f"{type(parser).__name__}")
        self.parser = parser if parser is not None else RulesParser()

    def edit(self, scene: Scene4D, text: str) -> Scene4D:
        """Apply an edit command; returns a new scene whose `undo()` is `scene`.

        Raises:
            CommandError: the text is not an edit command the parser understands (bad colour,
                speed factor <= 0, gibberish...).
            EditError: a target the scene does not have (the message lists its objects), an
                ambiguous target, or an operation that cannot apply (reversing a still object).
        """
        if not isinstance(scene, Scene4D):
            raise ValueError(f"Expected a Scene4D to edit, found {type(scene).__name__}")
        plan = self.parser.parse(text, scene)
        if plan.mode != "edit":
            raise CommandError(f"Expected an edit command (e.g. 'make the {scene.objects[-1].name} blue'), found a "
                               f"description of a new scene: {text!r}; use MorphoSim.generate for that")
        result = scene
        for op in plan.edits:
            result = self.apply(result, op)
        prov = scene.provenance
        return result.derive(None, provenance=Provenance(prov.prompt, prov.seed, prov.generator, prov.reconstruction,
                                                         prov.edits + (text.strip(),), prov.substitutions),
                             parent=scene)

    # ------------------------------------------------------------- one op
    def select(self, scene: Scene4D, op: Any) -> Selection:
        """The Gaussians of an operation's targets."""
        ids = sorted({i for t in op.targets for i in t.object_ids})
        if not ids:
            raise EditError(f"Expected the edit to name objects of the scene, found none; objects: {scene.object_names}")
        query = " and ".join(t.noun if t.noun != "*" else "everything" for t in op.targets)
        sel = self.selector.select(scene, ids, query)
        if not sel.mask.any():
            raise EditError(f"The selection for {query!r} is empty in this scene; objects: {scene.object_names}")
        return sel

    def apply(self, scene: Scene4D, op: EditOp) -> Scene4D:
        """Apply one parsed `EditOp` (no history entry of its own)."""
        handler = _HANDLERS.get(type(op))
        if handler is None:
            raise EditError(f"Unsupported edit operation {getattr(op, 'op', type(op).__name__)!r}")
        if isinstance(op, CameraOp) or not op.targets:
            return handler(scene, op, None)
        return handler(scene, op, self.select(scene, op))


# -- one handler per edit kind: (scene, op, selection of its targets) -> new scene ------------------------


def _recolor(scene: Scene4D, op: RecolorOp, sel: Selection) -> Scene4D:
    return ops.recolor(scene, sel.mask, op.mode, rgb=None if op.color is None else op.color.rgb,
                       delta=op.delta, factor_rgb=op.factor_rgb)


def _remove(scene: Scene4D, op: RemoveOp, sel: Selection) -> Scene4D:
    return ops.remove(scene, sel.mask)


def _extract(scene: Scene4D, op: ExtractOp, sel: Selection) -> Scene4D:
    return ops.extract(scene, sel.mask)


def _reverse(scene: Scene4D, op: ReverseOp, sel: Selection) -> Scene4D:
    return ops.reverse(scene, list(sel.object_ids))


def _stop(scene: Scene4D, op: StopOp, sel: Selection) -> Scene4D:
    return ops.stop(scene, list(sel.object_ids))


def _speed(scene: Scene4D, op: SpeedOp, sel: Selection) -> Scene4D:
    factor = op.factor if op.factor is not None else op.speed
    return ops.change_speed(scene, list(sel.object_ids), float(factor))


def _redirect(scene: Scene4D, op: RedirectOp, sel: Selection) -> Scene4D:
    ids = list(sel.object_ids)
    if op.path not in (None, "straight"):
        raise EditError(f"Changing a motion's path shape to {op.path!r} is not supported by the editor; "
                        f"it can reverse, redirect (a new direction or a landmark), change speed or stop")
    direction = op.direction_world
    if op.end is not None:
        goal = scene.object_center(op.end, 0.0)
        here = np.mean([scene.object_center(i, 0.0) for i in ids], axis=0)
        d = goal - here
        d[2] = 0.0
        if np.linalg.norm(d) < 1e-9:
            raise EditError(f"Cannot head towards {op.end!r}: the object is already there")
        direction = tuple(d / np.linalg.norm(d))
    if direction is None:
        raise EditError("Expected a new direction or a landmark for the redirect, found neither")
    if op.factor is None and op.speed is None:
        _refuse_same_direction(scene, ids, direction)
    out = ops.redirect(scene, ids, direction)
    if op.factor is not None or op.speed is not None:
        out = ops.change_speed(out, ids, float(op.factor if op.factor is not None else op.speed))
    return out


def _refuse_same_direction(scene: Scene4D, ids: list[int], direction: Any) -> None:
    """A redirect to where the objects already go would change nothing: an `EditError` saying so."""
    heading = ops.main_direction(scene, ids)
    want = np.asarray(direction, dtype=np.float64)
    if heading is not None and float(heading @ want) / float(np.linalg.norm(want)) > 0.97:
        names = [o.name for o in scene.objects if o.id in set(ids)]
        raise EditError(f"Nothing to change: {', '.join(names)} already moves that way "
                        f"(direction {tuple(round(float(c), 2) + 0.0 for c in heading)}); to change how fast, say e.g. "
                        f"'make the {names[0]} faster'")


def _camera(scene: Scene4D, op: CameraOp, sel: None) -> Scene4D:
    spec = op.camera
    base = scene.cameras[0]
    centre = scene.centre()
    cams = camera_path(spec, base, centre, scene.num_frames)
    return scene.derive(None, cameras=tuple(cams) if len(set(map(id, cams))) > 1 else (cams[0],))


_HANDLERS: dict[type, Callable[[Scene4D, Any, Any], Scene4D]] = {
    RecolorOp: _recolor, RemoveOp: _remove, ExtractOp: _extract, ReverseOp: _reverse, StopOp: _stop,
    SpeedOp: _speed, RedirectOp: _redirect, CameraOp: _camera, **AXIS_HANDLERS,
}

