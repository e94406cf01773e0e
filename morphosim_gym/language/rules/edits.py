"""Edit reading: one edit segment -> op drafts (dicts of `EditOp` fields, targets not yet resolved)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from ...errors import CommandError
from ..colors import COLOR_MODIFIERS, MODIFIER_SYNONYMS, color_rgb, match_color
from ..lexicon import (
    ADDITIVE_COLORS,
    BRIGHTER,
    DARKER,
    DETS,
    DIRECTION_WORDS,
    EDIT_VERBS,
    FILLER,
    LEFTOVER_OK,
    PRONOUNS,
)
from ..plan import CameraSpec, ColorSpec
from ..vocabulary import noun_to_category, singular
from .camera import read_camera
from .motion import Predicate, combine_directions
from .nouns import parse_np
from .scanner import PhraseScanner
from .segments import skip_preamble
from .tokens import detok, known_word, number_at, stop_word

__all__ = ["TargetDraft", "EditReader"]


@dataclass
class TargetDraft:
    text: str
    kind: str  # noun | pronoun | all | camera
    noun: str = ""
    color: tuple[str, tuple[float, float, float]] | None = None
    plural: bool = False


class EditReader:
    """Reads one edit segment into op drafts (dicts of EditOp fields, targets unresolved)."""

    def __init__(self, toks: list[str]) -> None:
        self.toks = toks
        self.seg = detok(toks)

    def fail(self, why: str) -> CommandError:
        return CommandError(f"Could not understand the edit {self.seg!r}: {why}. Supported edits: recolour "
                            f"('make the bus yellow', 'make it redder', 'make it darker'), remove ('delete the ball'), "
                            f"extract ('extract the boat'), reverse ('reverse its motion'), redirect ('move the ball to "
                            f"the left'), speed ('make the car twice as fast'), stop ('stop the dog'), camera "
                            f"('orbit the camera clockwise', 'pan left', 'zoom in')")

    def read(self) -> list[dict]:
        toks = self.toks
        if toks and toks[0] == "__camera__":
            cam = read_camera(toks[1:])
            return [self._camera_op(cam)]
        ops: list[dict] = []
        parts = self._split_ops(toks)
        prev: dict | None = None
        for part in parts:
            part = skip_preamble(part)
            if not part:
                continue
            got = self._read_one(part, prev)
            ops.extend(got)
            prev = got[-1] if got else prev
        if not ops:
            raise self.fail("no edit found")
        return ops

    def _split_ops(self, toks: list[str]) -> list[list[str]]:
        """Split "make the cube blue and reverse its motion" at "and"/"," before an edit verb."""
        parts: list[list[str]] = []
        cur: list[str] = []
        i = 0
        while i < len(toks):
            w = toks[i]
            if w in ("and", ",", "but") and cur:
                j = i + 1
                while j < len(toks) and toks[j] in ("and", ",", "also", "then", "please"):
                    j += 1
                if j < len(toks) and toks[j] in EDIT_VERBS and toks[j] not in ("show",):
                    # "make it stop and ..." keeps going; "... and delete the car" starts a new op
                    if not (cur[0] in ("make", "let", "have") and toks[j] in ("move", "go", "stop", "bounce", "run",
                                                                              "fly", "drive", "swim", "roll")
                            and self._make_has_no_complement(cur)):
                        parts.append(cur)
                        cur = []
                        i = j
                        continue
                # gapping: "make the ball blue and the cube red"
                if cur and cur[0] in ("make", "turn", "paint", "color", "colour", "dye") and j < len(toks) and \
                        toks[j] in DETS | {"it"} and any(match_color(cur, k) is not None for k in range(2, len(cur))):
                    np_ = parse_np(toks, j, edit=True)
                    if np_ is not None and np_.end < len(toks) and (match_color(toks, np_.end) is not None
                                                                    or toks[np_.end] in ADDITIVE_COLORS):
                        parts.append(cur)
                        cur = [cur[0]]
                        i = j
                        continue
            cur.append(w)
            i += 1
        if cur:
            parts.append(cur)
        return parts

    @staticmethod
    def _make_has_no_complement(cur: list[str]) -> bool:
        np_ = parse_np(cur, 1, edit=True)
        return np_ is not None and np_.end >= len(cur)

    # one operation ------------------------------------------------------------------------------------------
    def _read_one(self, toks: list[str], prev: dict | None) -> list[dict]:
        w = toks[0]
        rest = toks[1:]
        if w == "__camera__":
            return [self._camera_op(read_camera(rest))]
        if w in ("make", "let", "have", "turn", "get"):
            if w == "turn" and rest and rest[0] in ("the", "camera") and "camera" in rest[:2]:
                return [self._camera_op(read_camera(toks))]
            return self._make(rest, verb=w)
        if w in ("paint", "color", "colour", "recolor", "recolour", "dye", "colorize", "recolorize", "shade"):
            targets, k = self._targets(rest)
            tail = [x for x in rest[k:] if x not in ("to", "into", "in", "with", "a", "an")]
            return [self._recolor(targets, tail, assign=True)]
        if w == "tint":
            targets, k = self._targets(rest)
            tail = [x for x in rest[k:] if x not in ("to", "into", "in", "with", "a", "an", "slightly", "bit")]
            col = match_color(tail)
            if col is None:
                raise self.fail("expected a colour to tint with")
            return [self._additive(targets, col, 0.3)]
        if w in ("change", "set", "switch", "alter", "apply"):
            return self._change(rest)
        if w == "give":
            targets, k = self._targets(rest)
            tail = rest[k:]
            col = None
            for j in range(len(tail)):
                col = match_color(tail, j)
                if col is not None:
                    break
            if col is not None and any(x in ("tint", "hue", "shade", "touch") for x in tail):
                return [self._additive(targets, col, 0.3)]
            if col is not None:
                return [self._recolor(targets, [col[0]], assign=True)]
            raise self.fail("expected 'give X a <colour> tint'")
        if w == "add":
            tail = rest
            amount = 0.3
            j = 0
            while j < len(tail) and tail[j] in ("some", "a", "bit", "of", "little", "more", "touch", "hint", "lot",
                                                "alot", "much"):
                if tail[j] in ("bit", "little", "touch", "hint"):
                    amount = 0.15
                if tail[j] in ("lot", "alot", "much"):
                    amount = 0.5
                j += 1
            col = match_color(tail, j)
            if col is None:
                raise self.fail("adding objects is not supported in an edit (describe them when generating); "
                                "'add some blue to X' adds colour")
            k = j + col[2]
            while k < len(tail) and tail[k] in ("to", "onto", "on", "color", "tint"):
                k += 1
            targets, _ = self._targets(tail[k:])
            return [self._additive(targets, col, amount)]
        if w in ("darken", "dim", "blacken"):
            targets, k = self._targets(rest)
            return [self._multiply(targets, DARKER.get(w, 0.6) * self._amount_mult(rest[k:]))]
        if w in ("brighten", "lighten", "whiten"):
            targets, k = self._targets(rest)
            return [self._multiply(targets, BRIGHTER.get(w, 1.5))]
        if w == "redden":
            targets, _ = self._targets(rest)
            return [self._additive(targets, ("red", color_rgb("red"), 1), 0.3)]
        if w in ("delete", "remove", "erase", "eliminate", "discard", "getridof", "hide", "clear", "drop", "wipe"):
            if rest and rest[0] in ("out",):
                rest = rest[1:]
            targets, k = self._targets(rest)
            self._no_leftover(rest[k:])
            return [dict(op="remove", targets=targets)]
        if w == "take" and rest and (rest[0] in ("out", "away") or rest[-1] in ("out", "away")):
            r = rest[1:] if rest[0] in ("out", "away") else rest[:-1]
            targets, k = self._targets(r)
            self._no_leftover(r[k:])
            return [dict(op="remove", targets=targets)]
        if w in ("extract", "isolate", "segment", "separate", "single", "pull", "cut", "keep", "show", "only"):
            r = [x for x in rest if x not in ("out", "only", "just")]
            if w in ("keep", "show") and not (rest and rest[0] in ("only", "just")) and not (
                    len(rest) > 1 and rest[-1] in ("only",)):
                if w == "keep" and rest:
                    # "keep the ball moving" / "keep the camera still"
                    return self._make(rest, verb="keep")
                raise self.fail(f"expected '{w} only X'")
            targets, k = self._targets(r)
            self._no_leftover(r[k:])
            return [dict(op="extract", targets=targets)]
        if w in ("reverse", "invert", "flip"):
            r = [x for x in rest if x not in ("the", "direction", "directions", "motion", "movement", "of", "trajectory",
                                              "path", "course", "heading", "velocity", "'s")]
            if not r and rest:
                r = rest
            targets, k = self._targets(r or ["it"])
            self._no_leftover((r or ["it"])[k:])
            return [dict(op="reverse", targets=targets)]
        if w in ("stop", "halt", "freeze", "pause"):
            r = [x for x in rest if x not in ("from", "moving", "motion", "the", "movement", "of")]
            if not r:
                r = ["it"]
            if "camera" in rest:
                return [self._camera_op({"motion": "fixed"})]
            targets, _ = self._targets(rest if rest and rest[0] in DETS | PRONOUNS | {"all", "everything"} else r)
            return [dict(op="stop", targets=targets)]
        if w in ("speed", "slow", "accelerate", "decelerate", "double", "halve", "triple", "quadruple", "increase",
                 "decrease", "reduce"):
            return [self._speed_verb(w, rest)]
        if w in ("orbit", "circle", "rotate", "pan", "zoom", "dolly"):
            if w in ("orbit", "circle", "rotate") and rest and "camera" not in rest and not any(
                    x in ("view", "viewpoint", "shot") for x in rest):
                # "circle the ball around the tree": a path change
                targets, k = self._targets(rest)
                return self._motion_ops(targets, ["circle"] + rest[k:], implied="circle")
            return [self._camera_op(read_camera(toks))]
        if w in ("move", "send", "steer", "direct", "guide", "redirect", "bounce", "zigzag", "go", "drive", "fly",
                 "roll", "run", "swim", "sail", "head"):
            if rest and "camera" in rest[:3]:
                return [self._camera_op(read_camera(toks))]
            if w in ("go", "head", "drive", "fly", "run", "swim", "sail", "roll") and (not rest or rest[0] not in
                                                                                       DETS | PRONOUNS):
                raise self.fail(f"'{w}' needs an object: say which object should {w}")
            targets, k = self._targets(rest)
            implied = {"bounce": "bounce", "zigzag": "zigzag"}.get(w)
            return self._motion_ops(targets, rest[k:], implied=implied, verb=w)
        raise self.fail(f"'{w}' is not an edit this parser knows")

    def _no_leftover(self, rest: Sequence[str]) -> None:
        """Words after the targets of remove/extract/reverse must be fillers ("from the scene"), so that
        "delete everything except the ball" fails instead of deleting everything."""
        extra = [w for w in rest if w not in LEFTOVER_OK]
        if extra:
            raise self.fail(f"could not read {' '.join(rest)!r} after what to edit")

    # targets -------------------------------------------------------------------------------------------------
    def _targets(self, toks: list[str], required: bool = True) -> tuple[list[TargetDraft], int]:
        """Parse "the fish and seaweed", "it", "all the balls", "everything", "the camera"."""
        out: list[TargetDraft] = []
        i = 0
        n = len(toks)
        while i < n:
            w = toks[i]
            if w in ("and", ",", "both", "also") and out or w in ("both",):
                i += 1
                continue
            if w in ("everything", "everybody", "everyone") or (w == "all" and (i + 1 >= n or toks[i + 1] in (
                    "objects", "things", "the", "of", "items", "and", ","))) and not (
                    i + 2 < n and toks[i + 1] == "the" and toks[i + 2] not in ("objects", "things", "items", "scene")):
                j = i + 1
                while j < n and toks[j] in ("objects", "things", "the", "of", "items", "them", "in", "scene"):
                    j += 1
                out.append(TargetDraft(text=" ".join(toks[i:j]), kind="all", noun="*"))
                i = j
                if i < n and toks[i] in ("and", ","):
                    continue
                break
            if w in ("the", "whole", "entire") and i + 1 < n and toks[i + 1] in ("scene", "whole", "entire", "world"):
                j = i + 1
                while j < n and toks[j] in ("whole", "entire", "scene", "world"):
                    j += 1
                out.append(TargetDraft(text=" ".join(toks[i:j]), kind="all", noun="*"))
                i = j
                break
            if w in ("it", "them", "they", "its", "their", "itself", "this", "that", "these", "those") and (
                    i + 1 >= n or stop_word(toks[i + 1]) or toks[i + 1] in ("'s", "motion", "movement", "direction",
                                                                            "speed", "color", "path", "one", "ones")
                    or match_color(toks, i + 1) is not None or toks[i + 1] in ADDITIVE_COLORS or toks[i + 1] in DARKER
                    or toks[i + 1] in BRIGHTER or w in ("it", "them", "they", "its", "their", "itself")):
                j = i + 1
                if j < n and toks[j] in ("one", "ones"):
                    j += 1
                out.append(TargetDraft(text=w, kind="pronoun", noun=w, plural=w in ("them", "they", "their")))
                i = j
                if i < n and toks[i] == "'s":
                    i += 1
                break_ok = True
                if i < n and toks[i] in ("and", ",") and i + 1 < n and (toks[i + 1] in DETS or toks[i + 1] in PRONOUNS):
                    continue
                if break_ok:
                    break
            np_ = parse_np(toks, i, edit=True)
            if np_ is None:
                break
            if np_.kind == "camera":
                out.append(TargetDraft(text=np_.text, kind="camera", noun="camera"))
            elif np_.kind == "all" or (np_.kind == "generic" and np_.det in ("all", "every", "each")):
                out.append(TargetDraft(text=np_.text, kind="all", noun="*"))
            elif np_.kind == "pronoun":
                out.append(TargetDraft(text=np_.text, kind="pronoun", noun=np_.head, plural=np_.plural))
            elif np_.kind == "viewer":
                break
            else:
                noun = singular(np_.head) if np_.plural or np_.kind == "unknown" else np_.head
                out.append(TargetDraft(text=np_.text, kind="noun", noun=noun, color=np_.color,
                                        plural=np_.plural))
            i = np_.end
            if i < n and toks[i] == "'s":
                i += 1
                break
            if i < n and toks[i] in ("and", ","):
                j = i + 1
                while j < n and toks[j] in ("and", ","):
                    j += 1
                if j < n and (toks[j] in DETS or toks[j] in PRONOUNS or noun_to_category(toks[j]) is not None
                              or (toks[j] not in EDIT_VERBS and not stop_word(toks[j])
                                  and match_color(toks, j) is None and toks[j] not in ADDITIVE_COLORS)):
                    nxt = parse_np(toks, j, edit=True)
                    if nxt is not None and nxt.kind not in ("viewer",):
                        i = j
                        continue
            break
        if not out and required:
            raise self.fail("expected what to edit (e.g. 'the ball', 'it', 'everything')")
        return out, i

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
        tail = [x for x in tail if x not in ("be", "look", "become", "appear", "seem", "to", "please")] if not (
            tail and tail[0] in ("to", "toward")) else tail
        if not tail:
            raise self.fail("nothing says what to change")
        if any(t.kind == "camera" for t in targets):
            return [self._camera_target_ops(targets, tail)]
        t0 = tail[0]
        if t0 in ("bigger", "smaller", "larger", "taller", "shorter", "wider", "thinner", "huge", "tiny", "big",
                  "small", "large"):
            raise self.fail("resizing objects is not supported")
        if t0 in ("disappear", "vanish", "invisible", "gone", "hidden") or tail[:2] == ["go", "away"]:
            return [dict(op="remove", targets=targets)]
        if t0 in ("stop", "halt", "freeze", "still", "stationary", "static", "motionless", "pause") or tail[:2] in (
                ["stand", "still"], ["stay", "still"], ["not", "move"], ["stay", "put"], ["come", "to"],
                ["keep", "still"], ["stop", "moving"]):
            return [dict(op="stop", targets=targets)]
        if t0 in ("reverse", "backwards", "backward") or tail[-2:] == ["in", "reverse"] or tail[:2] in (["go", "back"], ["turn", "around"],
                                                                       ["move", "backwards"], ["go", "backwards"],
                                                                       ["move", "backward"], ["go", "backward"],
                                                                       ["run", "backwards"]) \
                or ("opposite" in tail and ("way" in tail or "direction" in tail)) or tail[-2:] == ["other", "way"]:
            return [dict(op="reverse", targets=targets)]
        # colour complements
        op = self._colour_complement(targets, tail)
        if op is not None:
            return [op]
        if verb == "turn" and (t0 in ("left", "right", "around") or t0 in DIRECTION_WORDS):
            if t0 == "around":
                return [dict(op="reverse", targets=targets)]
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
        tail = [x for x in tail if x not in ("a", "an", "some", "into", "in", "colored", "painted", "look")]
        if not tail:
            return None
        amount_mult = self._amount_mult(tail)
        core = [x for x in tail if x not in ("slightly", "bit", "little", "much", "alot", "lot", "far", "way",
                                               "somewhat", "tad", "even", "more", "less", "a", "lot") or x in (
            "more", "less")]
        if not core:
            return None
        # multiplicative
        if core[0] in DARKER or core[0] in BRIGHTER:
            f = DARKER.get(core[0]) or BRIGHTER[core[0]]
            if core[0] in DARKER:
                f = {1.0: f, 2.0: 0.4, 0.5: 0.8}[amount_mult]
            else:
                f = {1.0: f, 2.0: 2.0, 0.5: 1.25}[amount_mult]
            return self._multiply(targets, f)
        if core[:3] in (["half", "as", "bright"], ["half", "as", "light"]):
            return self._multiply(targets, 0.5)
        if core[:3] in (["twice", "as", "bright"], ["double", "as", "bright"]):
            return self._multiply(targets, 2.0)
        if len(core) >= 3 and number_at(core, 0) is not None and core[1] == "times" and core[2] in (
                "brighter", "darker", "as"):
            v = number_at(core, 0)[0]
            if v <= 0:
                raise self.fail("a brightness factor must be > 0")
            return self._multiply(targets, float(v) if core[2] in ("brighter", "as") else 1.0 / v)
        # additive
        if core[0] in ADDITIVE_COLORS:
            name = ADDITIVE_COLORS[core[0]]
            return self._additive(targets, (name, color_rgb(name), 1), 0.3 * amount_mult)
        if core[0] in ("more", "less") and len(core) > 1:
            col = match_color(core, 1)
            if col is not None:
                return self._additive(targets, col, (0.3 if core[0] == "more" else -0.3) * amount_mult)
            if core[1] in ("bright", "vivid", "vibrant", "dark", "light"):
                bright = core[1] in ("bright", "vivid", "vibrant", "light")
                up = core[0] == "more"
                return self._multiply(targets, 1.5 if bright == up else 0.6)
        # assign
        col = match_color(core, 0)
        if col is not None:
            rest = [x for x in core[col[2]:] if x not in FILLER]
            if rest and rest[0] in ("and",):
                rest = []
            if rest:
                if any(x in ("tint", "tinge", "hue") for x in core):
                    return self._additive(targets, col, 0.3 * amount_mult)
                return None
            if any(x in ("tint", "tinge") for x in tail):
                return self._additive(targets, col, 0.3 * amount_mult)
            return self._recolor(targets, [col[0]] if " " not in col[0] else col[0].split(), assign=True)
        if core[0] in COLOR_MODIFIERS or core[0] in MODIFIER_SYNONYMS:
            if len(core) > 1 and core[1].isalpha() and not known_word(core[1]):
                raise self.fail(f"unknown colour {core[1]!r}; colours are the CSS names (e.g. red, navy, lightblue) "
                                f"optionally after light/dark/pale/bright")
        return None

    @staticmethod
    def _amount_mult(tail: Sequence[str]) -> float:
        if any(x in ("much", "alot", "lot", "far", "way", "considerably") for x in tail):
            return 2.0
        if any(x in ("slightly", "bit", "little", "somewhat", "tad", "touch") for x in tail):
            return 0.5
        return 1.0

    def _recolor(self, targets: list[TargetDraft], tail: list[str], assign: bool = True) -> dict:
        tail = [x for x in tail if x not in ("to", "into", "in", "a", "an", "the", "color", "colour", "as", "well")]
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
        return dict(op="recolor", targets=targets, mode="assign", color=ColorSpec(col[0], col[1]))

    @staticmethod
    def _additive(targets: list[TargetDraft], col: tuple, amount: float) -> dict:
        amount = max(-1.0, min(1.0, amount))
        delta = tuple(round(amount * c, 6) + 0.0 for c in col[1])
        return dict(op="recolor", targets=targets, mode="additive", color=ColorSpec(col[0], col[1]), delta=delta)

    def _multiply(self, targets: list[TargetDraft], f: float) -> dict:
        if f <= 0:
            raise self.fail("a brightness factor must be > 0")
        f = round(f, 6)
        return dict(op="recolor", targets=targets, mode="multiplicative", factor_rgb=(f, f, f))

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
        while tail and tail[0] in ("to", "into", "a", "an", "from", "so", "that", "it", "is"):
            if tail[0] == "from":  # "change X from red to blue"
                k = tail.index("to") if "to" in tail else len(tail)
                tail = tail[k:]
                continue
            tail = tail[1:]
        if attr in ("color", "colors") or (attr is None and tail and (match_color(tail) is not None
                                                                      or tail[0] in ADDITIVE_COLORS)):
            return [self._recolor(targets, tail, assign=True)]
        if attr in ("direction", "motion", "path", "movement", "trajectory", "velocity"):
            if not tail or tail in (["around"],) or tail[0] in ("opposite", "reverse", "reversed", "backwards"):
                return [dict(op="reverse", targets=targets)]
            return self._motion_ops(targets, tail, verb="change")
        if attr == "speed":
            if not tail:
                raise self.fail("expected a new speed (e.g. 'change the speed of the car to slow')")
            return self._motion_ops(targets, tail, verb="change", speed_only=True)
        return self._complement(targets, tail, "change")

    # speed --------------------------------------------------------------------------------------------------
    def _speed_verb(self, w: str, rest: list[str]) -> dict:
        r = list(rest)
        factor: float | None = None
        if w in ("speed", "slow"):
            if r and r[0] in ("up", "down"):
                r = r[1:]
            elif r and r[-1] in ("up", "down"):
                r = r[:-1]
            factor = 2.0 if w == "speed" else 0.5
        elif w in ("accelerate", "increase"):
            factor = 2.0
        elif w in ("decelerate", "decrease", "reduce"):
            factor = 0.5
        elif w == "double":
            factor = 2.0
        elif w == "halve":
            factor = 0.5
        elif w == "triple":
            factor = 3.0
        elif w == "quadruple":
            factor = 4.0
        r = [x for x in r if x not in ("the", "speed", "of", "'s", "velocity", "pace")] if (
            "speed" in r or "of" in r or "velocity" in r or "pace" in r) else r
        mult = self._amount_mult(r)
        if w in ("speed", "accelerate", "increase") and mult != 1.0:
            factor = {2.0: 3.0, 0.5: 1.25}[mult]
        if w in ("slow", "decelerate", "decrease", "reduce") and mult != 1.0:
            factor = {2.0: round(1 / 3, 6), 0.5: 0.8}[mult]
        r = [x for x in r if x not in ("a", "bit", "little", "lot", "alot", "much", "slightly", "way", "far")]
        by = None
        if "by" in r:
            k = r.index("by")
            by = r[k + 1:]
            r = r[:k]
        if not r:
            r = ["it"]
        targets, j = self._targets(r)
        if by:
            num = number_at(by, 0)
            if num is not None and len(by) > num[1] and by[num[1]] == "percent":
                p = num[0] / 100.0
                factor = 1 + p if w in ("speed", "accelerate", "increase") else 1 - p
            elif num is not None and len(by) > num[1] and by[num[1]] in ("times",):
                factor = float(num[0]) if w in ("speed", "accelerate", "increase") else (
                    1.0 / num[0] if num[0] else 0.0)
            elif by[:1] == ["half"]:
                factor = 1.5 if w in ("speed", "accelerate", "increase") else 0.5
        if factor is None or factor <= 0:
            raise self.fail("the speed factor must be > 0 (say 'stop' to stop a motion)")
        if targets and targets[0].kind == "camera":
            return dict(op="speed", targets=targets, factor=round(factor, 6))
        return dict(op="speed", targets=targets, factor=round(factor, 6))

    # motion ops ----------------------------------------------------------------------------------------------
    def _motion_ops(self, targets: list[TargetDraft], tail: list[str], implied: str | None = None,
                    verb: str | None = None, allow_fail: bool = False, speed_only: bool = False) -> list[dict]:
        pred = Predicate()
        scanner = PhraseScanner(tail, edit=True)
        scanner.scan(0, len(tail), pred)
        if tail and tail[0] in ("to", "at") and pred.speed is None and pred.factor is None and speed_only:
            pass
        if speed_only and pred.speed is None and pred.factor is None:
            num = number_at(tail, 0)
            if tail[:1] == ["half"]:
                pred.factor = 0.5
            elif tail[:1] in (["double"], ["twice"]):
                pred.factor = 2.0
            elif num is not None:
                if num[0] <= 0:
                    raise self.fail("the speed factor must be > 0 (say 'stop' to stop a motion)")
                pred.factor = float(num[0])
        if implied and not pred.path:
            pred.path = implied
        ops: list[dict] = []
        if pred.reverse and not (pred.dirs or pred.to_side or pred.end):
            return [dict(op="reverse", targets=targets)]
        direction = combine_directions(pred, tail)
        path = None
        kinds = [k for _, k in pred.verbs]
        if pred.path:
            path = pred.path
        elif pred.clockwise is not None or pred.around is not None:
            path = "circle"
        elif pred.oscillate:
            path = "oscillate"
            direction = direction or pred.oscillate_axis
        else:
            for k in ("zigzag", "circle", "bounce", "oscillate"):
                if k in kinds:
                    path = k
                    break
        if ("stop" in kinds or pred.stationary) and not (direction or path):
            return [dict(op="stop", targets=targets)]
        if pred.negated and ("move" in kinds or not kinds):
            return [dict(op="stop", targets=targets)]
        if direction is not None or path is not None or pred.end is not None or pred.around is not None:
            d: dict = dict(op="redirect", targets=targets, direction_world=direction, path=path,
                           clockwise=pred.clockwise if path == "circle" else None)
            if pred.end is not None:
                d["end_np"] = pred.end
            if pred.around is not None:
                d["around_np"] = pred.around
            ops.append(d)
        if pred.factor is not None:
            ops.append(dict(op="speed", targets=list(targets), factor=pred.factor))
        elif pred.speed is not None:
            ops.append(dict(op="speed", targets=list(targets), speed=pred.speed, speed_word=pred.speed_word))
        if not ops:
            if allow_fail:
                return []
            raise self.fail("expected a direction, path or speed (e.g. 'move the ball to the left')")
        return ops

    # camera --------------------------------------------------------------------------------------------------
    def _camera_op(self, cam: dict) -> dict:
        spec = CameraSpec(motion=cam.get("motion", "fixed"), direction=cam.get("direction"),
                          speed=cam.get("speed", 1.0), speed_word=cam.get("speed_word"))
        d = dict(op="camera", camera=spec)
        if cam.get("target_np") is not None:
            d["camera_target_np"] = cam["target_np"]
        return d

    def _camera_target_ops(self, targets: list[TargetDraft], tail: list[str]) -> dict:
        cam_t = [t for t in targets if t.kind == "camera"]
        pred = Predicate()
        PhraseScanner(tail, edit=True).scan(0, len(tail), pred)
        if pred.factor is not None:
            return dict(op="speed", targets=cam_t, factor=pred.factor)
        if pred.reverse:
            return dict(op="reverse", targets=cam_t)
        return self._camera_op(read_camera(["camera"] + tail))
