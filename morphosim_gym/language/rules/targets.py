"""Edit targets: drafts resolved against the scene or the plan, and turned into `EditOp`s."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import CommandError
from ..grounding import SceneItem, ground_noun, ground_noun_vocabulary, resolve_in_scene
from ..plan import CameraSpec, ColorSpec, EditOp, Target, edit_op
from ..vocabulary import singular
from .describe import ObjectDraft
from .edits import EditReader
from .nouns import NounPhrase
from .target_phrases import POSITION_WORDS, TargetDraft
from .tokens import detok

__all__ = ["TargetResolver", "target_from_hits"]


def target_from_hits(text: str, noun: str, hits: list[SceneItem]) -> Target:
    cats = {h.category for h in hits}
    return Target(text=text, noun=noun, category=cats.pop() if len(cats) == 1 else None,
                  objects=tuple(h.name for h in hits), object_ids=tuple(h.id for h in hits))


def _without_position(t: TargetDraft) -> str:
    return " ".join(w for w in t.text.split() if w not in POSITION_WORDS)


def pick_by_position(scene: Any, hits: list[SceneItem], position: str) -> SceneItem:
    """The hit the position word names, as the scene's generation camera sees the objects at t = 0:
    "left" / "right" the smallest / largest image x of its centre, "front" / "back" the nearest /
    farthest from the camera."""
    cam = scene.camera
    centres = np.array([scene.object_center(h.id, 0.0) for h in hits])
    uv, z = cam.project(centres)
    key = {"left": uv[:, 0], "right": -uv[:, 0], "front": z, "back": -z}[position]
    return hits[int(np.argmin(key))]


class TargetResolver:
    """Resolves edit drafts into `EditOp`s against the parse state of `RuleParser` (a mixin of it)."""

    # ---- edits -------------------------------------------------------------------------------------------
    def _edit_segment(self, toks: list[str]) -> list[EditOp]:
        drafts = EditReader(toks).read()
        ops: list[EditOp] = []
        for d in drafts:
            ops.append(self._finish_op(d, toks))
        return ops

    def _finish_op(self, d: dict, toks: list[str]) -> EditOp:
        targets = tuple(self._resolve(t, toks) for t in d.pop("targets", []))
        cam_target = d.pop("camera_target_np", None)
        if d["op"] == "camera":
            cam: CameraSpec = d["camera"]
            if cam_target is not None:
                name = None
                if cam_target.kind == "setting" or cam_target.head == "table":
                    name = None
                elif self.generated:
                    name = self._landmark(cam_target)
                elif self.items is not None:
                    hits = resolve_in_scene(singular(cam_target.head), self.items, cam_target.text)
                    name = hits[0].name
                else:
                    name = singular(cam_target.head)
                d["camera"] = CameraSpec(cam.motion, cam.direction, cam.speed, cam.speed_word, name)
            return edit_op(**d)
        end_np = d.pop("end_np", None)
        if end_np is not None:
            d["end"] = self._edit_landmark(end_np, toks)
        around_np = d.pop("around_np", None)
        if around_np is not None:
            d["around"] = self._edit_landmark(around_np, toks)
        return edit_op(targets=targets, **d)

    def _edit_landmark(self, np_: NounPhrase, toks: list[str]) -> str:
        if self.generated:
            return self._landmark(np_)
        if self.items is not None:
            hits = resolve_in_scene(singular(np_.head), self.items, np_.text)
            return hits[0].name
        return singular(np_.head) if np_.kind != "pronoun" else self._pronoun_name(np_.head, toks)

    def _pronoun_name(self, word: str, toks: list[str]) -> str:
        if self.salience:
            return self.salience[-1]
        raise CommandError(f"Could not tell what {word!r} refers to in {detok(toks)!r}: name the object")

    def _resolve(self, t: TargetDraft, toks: list[str]) -> Target:
        if t.kind == "camera":
            return Target(text=t.text, noun="camera", category="camera")
        if self.generated:  # a compound command: targets are the plan's objects
            return self._resolve_in_plan(t, toks)
        if self.items is None:
            return self._resolve_without_scene(t, toks)
        return self._resolve_in_scene(t, toks)

    def _resolve_without_scene(self, t: TargetDraft, toks: list[str]) -> Target:
        """A target as written, grounded to a category (pronouns: the last target named)."""
        if self.require_scene:
            raise CommandError(f"Could not apply the edit {detok(toks)!r}: there is no scene to edit (pass the "
                               f"scene, or describe one first, e.g. 'a ball rolls left; then {detok(toks)}')")
        if t.kind == "pronoun":
            if self.salience:
                name = self.salience[-1]
                g = self._last_ground.get(name)
                return Target(text=t.text, noun=name, category=g)
            raise CommandError(f"Could not tell what {t.text!r} refers to in {detok(toks)!r}: there is no scene "
                               f"and no object named before it; name the object (e.g. 'make the ball blue')")
        if t.kind == "all":
            return Target(text=t.text, noun="*", category=None)
        g = ground_noun(t.noun, settings=True)
        self.salience.append(t.noun)
        self._last_ground[t.noun] = g.category
        return Target(text=t.text, noun=t.noun, category=g.category,
                      color=ColorSpec(*t.color) if t.color else None)

    def _resolve_in_scene(self, t: TargetDraft, toks: list[str]) -> Target:
        """A target among the scene's objects (pronouns: the last target's objects, or the only object)."""
        items = self.items
        if t.kind == "pronoun":
            if self.scene_salience:
                hits = self.scene_salience[-1]
            else:
                fg = [it for it in items if not it.background]
                if len(fg) != 1:
                    raise CommandError(f"Could not tell what {t.text!r} refers to in {detok(toks)!r}: the scene has "
                                       f"{len(fg)} objects ({', '.join(it.name for it in fg) or 'none'}); name one")
                hits = fg
            return target_from_hits(t.text, hits[0].name if len(hits) == 1 else hits[0].category, hits)
        noun = "*" if t.kind == "all" else t.noun
        hits = resolve_in_scene(noun, items, t.text if t.position is None else _without_position(t), t.color[1]
                                if t.color else None)
        if t.position is not None:
            hits = [pick_by_position(self.scene, hits, t.position)]
        self.scene_salience.append(hits)
        cat = None if noun == "*" else (hits[0].category if len({h.category for h in hits}) == 1 else None)
        return Target(text=t.text, noun=noun, category=cat, objects=tuple(h.name for h in hits),
                      object_ids=tuple(h.id for h in hits), color=ColorSpec(*t.color) if t.color else None)

    def _resolve_in_plan(self, t: TargetDraft, toks: list[str]) -> Target:
        """A target among the objects of the plan being built (a compound command)."""
        if t.kind == "pronoun":
            objs = self._plan_pronoun(t, toks)
        elif t.kind == "all":
            objs = list(self.objects)
        else:
            objs = self._plan_objects_named(t)
        for o in objs:
            self._touch(o.name)
        cats = {o.category for o in objs}
        noun = "*" if t.kind == "all" else (objs[0].noun if t.kind == "pronoun" else t.noun)
        return Target(text=t.text, noun=noun, category=cats.pop() if len(cats) == 1 and noun != "*" else None,
                      objects=tuple(o.name for o in objs), color=ColorSpec(*t.color) if t.color else None)

    def _plan_pronoun(self, t: TargetDraft, toks: list[str]) -> list[ObjectDraft]:
        """ "it": the last object named; "them" after a single object: all moving objects."""
        if not self.salience:
            raise CommandError(f"Could not tell what {t.text!r} refers to in {detok(toks)!r}")
        if t.plural and len(self.salience) >= 2 and self._obj(self.salience[-1]).count == 1:
            names = [o.name for o in self.objects if not o.landmark] or [self.salience[-1]]
        else:
            names = [self.salience[-1]]
        return [self._obj(n) for n in names]

    def _plan_objects_named(self, t: TargetDraft) -> list[ObjectDraft]:
        """The plan's objects a noun names: by noun or name, else by category, else by meaning."""
        sing = singular(t.noun)
        objs = [o for o in self.objects if o.noun in (t.noun, sing) or o.name in (t.noun, sing)]
        if not objs:
            g = ground_noun_vocabulary(t.noun) or ground_noun_vocabulary(sing)
            if g is not None:
                objs = [o for o in self.objects if o.category == g.category]
        if not objs:
            items = [SceneItem(o.name, o.category, i) for i, o in enumerate(self.objects)]
            if not items:
                raise CommandError(f"Could not find {t.text!r}: the command names no objects")
            objs = [self._obj(h.name) for h in resolve_in_scene(t.noun, items, t.text)]
        if t.color is not None and len(objs) > 1:
            objs = [o for o in objs if o.color is not None and o.color.name == t.color[0]] or objs
        return objs
