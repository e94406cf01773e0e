"""Edit phrases: the complements of edit verbs ("... blue", "... twice as fast", "... to the left") read
into op drafts (dicts of `EditOp` fields, targets not yet resolved)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ...errors import CommandError
from ...colors import COLOR_MODIFIERS, MODIFIER_SYNONYMS, color_rgb, match_color
from ..lexicon import (
    ADDITIVE_COLORS,
    AMOUNT_FILLERS,
    AMOUNT_LESS,
    AMOUNT_MORE,
    AMOUNT_WORDS,
    BRIGHTER,
    CHANGE_FILLERS,
    COLOUR_COMPLEMENT_FILLERS,
    COPULAS,
    DARKER,
    DIRECTION_WORDS,
    FILLER,
    LEFTOVER_OK,
    MOTION_ATTRIBUTES,
    RECOLOR_FILLERS,
    REMOVE_COMPLEMENTS,
    RESIZE_WORDS,
    REVERSE_COMPLEMENTS,
    REVERSE_PHRASES,
    SLOW_DOWN_VERBS,
    SPEED_NOUN_FILLERS,
    SPEED_UP_VERBS,
    SPEED_VERB_FACTORS,
    STOP_COMPLEMENTS,
    STOP_PHRASES,
)
from ..plan import CameraSpec, ColorSpec
from .camera import read_camera
from .motion import Predicate, combine_directions
from .scanner import PhraseScanner
from .target_phrases import TargetDraft, read_targets
from .tokens import detok, known_word, number_at

__all__ = ["EditPhrases"]


class EditPhrases:
    """Reads the parts of one edit segment; `EditReader` reads the whole segment with it."""

    def __init__(self, toks: list[str]) -> None:
        self.toks = toks
        self.seg = detok(toks)

    def fail(self, why: str) -> CommandError:
        return CommandError(f"Could not understand the edit {self.seg!r}: {why}. Supported edits: recolour "
                            f"('make the bus yellow', 'make it redder', 'make it darker'), remove ('delete the ball'), "
                            f"extract ('extract the boat'), reverse ('reverse its motion'), redirect ('move the ball to "
                            f"the left'), speed ('make the car twice as fast'), stop ('stop the dog'), camera "
                            f"('orbit the camera clockwise', 'pan left', 'zoom in')")

    def _targets(self, toks: list[str], required: bool = True) -> tuple[list[TargetDraft], int]:
        """Parse "the fish and seaweed", "it", "all the balls", "everything", "the camera"."""
        return read_targets(toks, self.fail, required)

    def _no_leftover(self, rest: Sequence[str]) -> None:
        """Words after the targets of remove/extract/reverse must be fillers ("from the scene"), so that
        "delete everything except the ball" fails instead of deleting everything."""
        extra = [w for w in rest if w not in LEFTOVER_OK]
        if extra:
            raise self.fail(f"could not read {' '.join(rest)!r} after what to edit")

    # "make ..." -----------------------------------------------------------------------------------------------
    def _make(self, rest: list[str], verb: str = "make") -> list[dict]:
        # "make the color of X C", "make X's color C"
        r = list(rest)
        if r[:3] in (["the", "color", "of"], ["the", "colors", "of"]) or r[:2] == ["color", "of"]:
            k = r.index("of")
            targets, j = self._targets(r[k + 1:])
            tail = r[k + 1 + j:]
            return [self._recolor(targets, tail, assign=True)]
        if r and r[0] == "the" and len(r) > 1 and r[1] == "camera" or r and r[0] == "camera":
            return [self._camera_op(read_camera(r))]
        targets, j = self._targets(r)
        tail = r[j:]
        if tail and tail[0] in ("color", "colors") and "of" not in tail[:1]:
            tail = tail[1:]
        return self._complement(targets, tail, verb)

    def _complement(self, targets: list[TargetDraft], tail: list[str], verb: str) -> list[dict]:
        """What follows "make X": a state ("disappear", "stop", "go backwards"), a colour, or a motion."""
        if not (tail and tail[0] in ("to", "toward")):
            tail = [x for x in tail if x not in COPULAS]
        if not tail:
            raise self.fail("nothing says what to change")
        if any(t.kind == "camera" for t in targets):
            return [self._camera_target_ops(targets, tail)]
        t0 = tail[0]
        if t0 in RESIZE_WORDS:
            raise self.fail("resizing objects is not supported")
        state = _state_complement(tail)
        if state is not None:
            return [{"op": state, "targets": targets}]
        op = self._colour_complement(targets, tail)
        if op is not None:
            return [op]
        if verb == "turn" and (t0 in ("left", "right", "around") or t0 in DIRECTION_WORDS):
            if t0 == "around":
                return [{"op": "reverse", "targets": targets}]
            return self._motion_ops(targets, tail, verb="turn")
        # motion complements: speed, direction, path
        ops = self._motion_ops(targets, tail, verb=verb, allow_fail=True)
        if ops:
            return ops
        col_word = next((x for x in tail if x.isalpha() and not known_word(x) and x not in FILLER), None)
        if col_word is not None and len(tail) <= 3:
            raise self.fail(f"unknown colour or change {col_word!r}; colours are the CSS names (e.g. red, navy, "
                            f"lightblue, goldenrod) optionally after light/dark/pale/bright")
        raise self.fail(f"could not read {' '.join(tail)!r}")

    def _colour_complement(self, targets: list[TargetDraft], tail: list[str]) -> dict | None:
        """A colour change: brightness ("darker", "twice as bright"), added colour ("redder", "more
        blue"), or a new colour ("blue", "a light blue tint"); None when `tail` names none."""
        tail = [x for x in tail if x not in COLOUR_COMPLEMENT_FILLERS]
        if not tail:
            return None
        amount_mult = self._amount_mult(tail)
        core = [x for x in tail if x not in AMOUNT_WORDS or x in ("more", "less")]
        if not core:
            return None
        f = self._brightness_factor(core, amount_mult)
        if f is not None:
            return self._multiply(targets, f)
        return self._more_or_less(targets, core, amount_mult) or self._assigned_colour(targets, core, tail,
                                                                                       amount_mult)

    def _brightness_factor(self, core: list[str], amount_mult: float) -> float | None:
        c0 = core[0]
        if c0 in DARKER:
            return {1.0: DARKER[c0], 2.0: 0.4, 0.5: 0.8}[amount_mult]
        if c0 in BRIGHTER:
            return {1.0: BRIGHTER[c0], 2.0: 2.0, 0.5: 1.25}[amount_mult]
        if tuple(core[:3]) in (("half", "as", "bright"), ("half", "as", "light")):
            return 0.5
        if tuple(core[:3]) in (("twice", "as", "bright"), ("double", "as", "bright")):
            return 2.0
        num = number_at(core, 0) if len(core) >= 3 else None
        if num is not None and core[1] == "times" and core[2] in ("brighter", "darker", "as"):
            v = num[0]
            if v <= 0:
                raise self.fail("a brightness factor must be > 0")
            return float(v) if core[2] in ("brighter", "as") else 1.0 / v
        return None

    def _more_or_less(self, targets: list[TargetDraft], core: list[str], amount_mult: float) -> dict | None:
        """ "redder", "more blue", "less green", "more vivid"."""
        c0 = core[0]
        if c0 in ADDITIVE_COLORS:
            name = ADDITIVE_COLORS[c0]
            return self._additive(targets, (name, color_rgb(name), 1), 0.3 * amount_mult)
        if c0 not in ("more", "less") or len(core) < 2:
            return None
        col = match_color(core, 1)
        if col is not None:
            return self._additive(targets, col, (0.3 if c0 == "more" else -0.3) * amount_mult)
        if core[1] in ("bright", "vivid", "vibrant", "dark", "light"):
            bright = core[1] in ("bright", "vivid", "vibrant", "light")
            return self._multiply(targets, 1.5 if bright == (c0 == "more") else 0.6)
        return None

    def _assigned_colour(self, targets: list[TargetDraft], core: list[str], tail: list[str],
                         amount_mult: float) -> dict | None:
        """ "blue", "light blue", "a blue tint"; an unknown word after a colour modifier is an error."""
        col = match_color(core, 0)
        if col is None:
            if (core[0] in COLOR_MODIFIERS or core[0] in MODIFIER_SYNONYMS) and len(core) > 1 \
                    and core[1].isalpha() and not known_word(core[1]):
                raise self.fail(f"unknown colour {core[1]!r}; colours are the CSS names (e.g. red, navy, lightblue) "
                                f"optionally after light/dark/pale/bright")
            return None
        rest = [x for x in core[col[2]:] if x not in FILLER]
        if rest and rest[0] == "and":
            rest = []
        if rest:
            if any(x in ("tint", "tinge", "hue") for x in core):
                return self._additive(targets, col, 0.3 * amount_mult)
            return None
        if any(x in ("tint", "tinge") for x in tail):
            return self._additive(targets, col, 0.3 * amount_mult)
        return self._recolor(targets, [col[0]] if " " not in col[0] else col[0].split(), assign=True)

    @staticmethod
    def _amount_mult(tail: Sequence[str]) -> float:
        if any(x in AMOUNT_MORE for x in tail):
            return 2.0
        if any(x in AMOUNT_LESS for x in tail):
            return 0.5
        return 1.0

    def _recolor(self, targets: list[TargetDraft], tail: list[str], assign: bool = True) -> dict:
        tail = [x for x in tail if x not in RECOLOR_FILLERS]
        col = match_color(tail, 0) if tail else None
        if col is None:
            word = next((x for x in tail if x not in FILLER), None)
            if word is None:
                raise self.fail("expected a colour (e.g. 'make the bus yellow')")
            op = self._colour_complement(targets, tail)
            if op is not None:
                return op
            raise self.fail(f"unknown colour {' '.join(tail)!r}; colours are the CSS names (e.g. red, navy, lightblue, "
                            f"goldenrod) optionally after light/dark/pale/bright")
        leftover = [x for x in tail[col[2]:] if x not in FILLER and x not in (",", "and", "please")]
        if leftover:
            raise self.fail(f"could not read {' '.join(tail)!r} as one colour")
        return {"op": "recolor", "targets": targets, "mode": "assign", "color": ColorSpec(col[0], col[1])}

    @staticmethod
    def _additive(targets: list[TargetDraft], col: tuple, amount: float) -> dict:
        amount = max(-1.0, min(1.0, amount))
        delta = tuple(round(amount * c, 6) + 0.0 for c in col[1])
        return {"op": "recolor", "targets": targets, "mode": "additive", "color": ColorSpec(col[0], col[1]), "delta": delta}

    def _multiply(self, targets: list[TargetDraft], f: float) -> dict:
        if f <= 0:
            raise self.fail("a brightness factor must be > 0")
        f = round(f, 6)
        return {"op": "recolor", "targets": targets, "mode": "multiplicative", "factor_rgb": (f, f, f)}

    # change / set -----------------------------------------------------------------------------------------
    def _change(self, rest: list[str]) -> list[dict]:
        r = list(rest)
        if "camera" in r[:3]:
            return [self._camera_op(read_camera(r))]
        attr = None
        # "the color of X to C" / "X's color to C" / "X to C"
        if r[:1] == ["the"] and len(r) > 2 and r[1] in ("color", "colors", "direction", "speed", "motion", "path",
                                                        "movement", "trajectory", "velocity") and r[2] == "of":
            attr = r[1]
            targets, j = self._targets(r[3:])
            tail = r[3 + j:]
        else:
            targets, j = self._targets(r)
            tail = r[j:]
            if tail and tail[0] in ("color", "colors", "direction", "speed", "motion", "path", "movement",
                                    "trajectory", "velocity"):
                attr = tail[0]
                tail = tail[1:]
        while tail and tail[0] in CHANGE_FILLERS:
            if tail[0] == "from":  # "change X from red to blue"
                k = tail.index("to") if "to" in tail else len(tail)
                tail = tail[k:]
                continue
            tail = tail[1:]
        if attr in ("color", "colors") or (attr is None and tail and (match_color(tail) is not None
                                                                      or tail[0] in ADDITIVE_COLORS)):
            return [self._recolor(targets, tail, assign=True)]
        if attr in MOTION_ATTRIBUTES:
            if not tail or tail in (["around"],) or tail[0] in ("opposite", "reverse", "reversed", "backwards"):
                return [{"op": "reverse", "targets": targets}]
            return self._motion_ops(targets, tail, verb="change")
        if attr == "speed":
            if not tail:
                raise self.fail("expected a new speed (e.g. 'change the speed of the car to slow')")
            return self._motion_ops(targets, tail, verb="change", speed_only=True)
        return self._complement(targets, tail, "change")

    # speed --------------------------------------------------------------------------------------------------
    def _speed_verb(self, w: str, rest: list[str]) -> dict:
        """ "speed up the car", "slow the ball down a lot", "double its speed", "slow it by 50 percent"."""
        r = list(rest)
        if w in ("speed", "slow"):
            if r and r[0] in ("up", "down"):
                r = r[1:]
            elif r and r[-1] in ("up", "down"):
                r = r[:-1]
        if "speed" in r or "of" in r or "velocity" in r or "pace" in r:
            r = [x for x in r if x not in SPEED_NOUN_FILLERS]
        factor = _amount_adjusted(w, SPEED_VERB_FACTORS.get(w), self._amount_mult(r))
        r = [x for x in r if x not in AMOUNT_FILLERS]
        by = None
        if "by" in r:
            k = r.index("by")
            by = r[k + 1:]
            r = r[:k]
        targets, _ = self._targets(r or ["it"])
        if by:
            factor = _by_amount(w, by, factor)
        if factor is None or factor <= 0:
            raise self.fail("the speed factor must be > 0 (say 'stop' to stop a motion)")
        return {"op": "speed", "targets": targets, "factor": round(factor, 6)}

    # motion ops ----------------------------------------------------------------------------------------------
    def _motion_ops(self, targets: list[TargetDraft], tail: list[str], implied: str | None = None,
                    verb: str | None = None, allow_fail: bool = False, speed_only: bool = False) -> list[dict]:
        """The redirect and/or speed ops of a motion phrase ("to the left", "in circles", "faster")."""
        pred = Predicate()
        PhraseScanner(tail, edit=True).scan(0, len(tail), pred)
        if speed_only and pred.speed is None and pred.factor is None:
            self._bare_speed_factor(tail, pred)
        if implied and not pred.path:
            pred.path = implied
        if pred.reverse and not (pred.dirs or pred.to_side or pred.end):
            return [{"op": "reverse", "targets": targets}]
        direction, path = _edit_path(pred, combine_directions(pred, tail))
        kinds = [k for _, k in pred.verbs]
        if ("stop" in kinds or pred.stationary) and not (direction or path):
            return [{"op": "stop", "targets": targets}]
        if pred.negated and ("move" in kinds or not kinds):
            return [{"op": "stop", "targets": targets}]
        ops = _redirect_and_speed(targets, pred, direction, path)
        if not ops and not allow_fail:
            raise self.fail("expected a direction, path or speed (e.g. 'move the ball to the left')")
        return ops

    def _bare_speed_factor(self, tail: list[str], pred: Predicate) -> None:
        """ "change the speed to half / double / 3"."""
        num = number_at(tail, 0)
        if tail[:1] == ["half"]:
            pred.factor = 0.5
        elif tail[:1] in (["double"], ["twice"]):
            pred.factor = 2.0
        elif num is not None:
            if num[0] <= 0:
                raise self.fail("the speed factor must be > 0 (say 'stop' to stop a motion)")
            pred.factor = float(num[0])

    # camera --------------------------------------------------------------------------------------------------
    def _camera_op(self, cam: dict) -> dict:
        spec = CameraSpec(motion=cam.get("motion", "fixed"), direction=cam.get("direction"),
                          speed=cam.get("speed", 1.0), speed_word=cam.get("speed_word"))
        d = {"op": "camera", "camera": spec}
        if cam.get("target_np") is not None:
            d["camera_target_np"] = cam["target_np"]
        return d

    def _camera_target_ops(self, targets: list[TargetDraft], tail: list[str]) -> dict:
        cam_t = [t for t in targets if t.kind == "camera"]
        pred = Predicate()
        PhraseScanner(tail, edit=True).scan(0, len(tail), pred)
        if pred.factor is not None:
            return {"op": "speed", "targets": cam_t, "factor": pred.factor}
        if pred.reverse:
            return {"op": "reverse", "targets": cam_t}
        return self._camera_op(read_camera(["camera"] + tail))


def _state_complement(tail: list[str]) -> str | None:
    """The op of a state complement: "disappear" -> remove, "stand still" -> stop, "go backwards" -> reverse."""
    t0, head, last = tail[0], tuple(tail[:2]), tuple(tail[-2:])
    if t0 in REMOVE_COMPLEMENTS or head == ("go", "away"):
        return "remove"
    if t0 in STOP_COMPLEMENTS or head in STOP_PHRASES:
        return "stop"
    if t0 in REVERSE_COMPLEMENTS or last in (("in", "reverse"), ("other", "way")) or head in REVERSE_PHRASES \
            or ("opposite" in tail and ("way" in tail or "direction" in tail)):
        return "reverse"
    return None


def _amount_adjusted(verb: str, factor: float | None, mult: float) -> float | None:
    """ "speed up a lot" 3.0, "slow down a bit" 0.8."""
    if mult == 1.0:
        return factor
    if verb in SPEED_UP_VERBS:
        return {2.0: 3.0, 0.5: 1.25}[mult]
    if verb in SLOW_DOWN_VERBS:
        return {2.0: round(1 / 3, 6), 0.5: 0.8}[mult]
    return factor


def _by_amount(verb: str, by: list[str], factor: float | None) -> float | None:
    """ "by 50 percent", "by 3 times", "by half"."""
    up = verb in SPEED_UP_VERBS
    num = number_at(by, 0)
    unit = by[num[1]] if num is not None and len(by) > num[1] else None
    if unit == "percent":
        p = num[0] / 100.0  # type: ignore[index]
        return 1 + p if up else 1 - p
    if unit == "times":
        return float(num[0]) if up else (1.0 / num[0] if num[0] else 0.0)  # type: ignore[index]
    if by[:1] == ["half"]:
        return 1.5 if up else 0.5
    return factor


def _edit_path(pred: Predicate, direction: Any) -> tuple[Any, str | None]:
    """The (direction, path shape) an edit's motion phrase asks for."""
    if pred.path:
        return direction, pred.path
    if pred.clockwise is not None or pred.around is not None:
        return direction, "circle"
    if pred.oscillate:
        return direction or pred.oscillate_axis, "oscillate"
    kinds = [k for _, k in pred.verbs]
    return direction, next((k for k in ("zigzag", "circle", "bounce", "oscillate") if k in kinds), None)


def _redirect_and_speed(targets: list[TargetDraft], pred: Predicate, direction: Any, path: str | None) -> list[dict]:
    """A redirect op (a direction, path, end or centre) and/or a speed op (a factor or speed words)."""
    ops: list[dict] = []
    if direction is not None or path is not None or pred.end is not None or pred.around is not None:
        d: dict = {"op": "redirect", "targets": targets, "direction_world": direction, "path": path,
                   "clockwise": pred.clockwise if path == "circle" else None}
        if pred.end is not None:
            d["end_np"] = pred.end
        if pred.around is not None:
            d["around_np"] = pred.around
        ops.append(d)
    if pred.factor is not None:
        ops.append({"op": "speed", "targets": list(targets), "factor": pred.factor})
    elif pred.speed is not None:
        ops.append({"op": "speed", "targets": list(targets), "speed": pred.speed, "speed_word": pred.speed_word})
    return ops
