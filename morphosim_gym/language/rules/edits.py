"""Edit reading: one edit segment -> op drafts (dicts of `EditOp` fields, targets not yet resolved).

A segment is split into operations at "and"/"," before an edit verb; each operation is read by
the reader of its first word (`_VERB_READERS`, keyed by the verb groups of
`lexicon.EDIT_VERB_GROUPS`).
"""

from __future__ import annotations

from collections.abc import Callable

from ...colors import color_rgb, match_color
from ...errors import CommandError
from ..lexicon import (
    ADDITIVE_COLORS,
    BRIGHTER,
    DARKER,
    DETS,
    EDIT_VERB_GROUPS,
    EDIT_VERBS,
    GAPPING_VERBS,
    MAKE_MOTION_VERBS,
    MOTION_VERBS_NEEDING_OBJECT,
    PAINT_FILLERS,
    PRONOUNS,
    STOP_FILLERS,
    TINT_FILLERS,
)
from .axis_edits import AXIS_READERS
from .camera import read_camera
from .edit_phrases import EditPhrases
from .nouns import parse_np
from .segments import skip_preamble

__all__ = ["EditReader"]

Reader = Callable[["EditReader", str, list[str], list[str]], list[dict]]


class EditReader(EditPhrases):
    """Reads one edit segment into op drafts (dicts of EditOp fields, targets unresolved)."""

    def read(self) -> list[dict]:
        toks = self.toks
        if toks and toks[0] == "__camera__":
            cam = read_camera(toks[1:])
            return [self._camera_op(cam)]
        ops: list[dict] = []
        for part in self._split_ops(toks):
            part = skip_preamble(part)
            if part:
                ops.extend(self._read_one(part))
        if not ops:
            raise self.fail("no edit found")
        return ops

    def _split_ops(self, toks: list[str]) -> list[list[str]]:
        """Split "make the cube blue and reverse its motion" at "and"/"," before an edit verb."""
        parts: list[list[str]] = []
        cur: list[str] = []
        i = 0
        while i < len(toks):
            if toks[i] in ("and", ",", "but") and cur:
                j = i + 1
                while j < len(toks) and toks[j] in ("and", ",", "also", "then", "please"):
                    j += 1
                cut = self._new_op_at(toks, j, cur)
                if cut is not None:
                    parts.append(cur)
                    cur, i = cut, j
                    continue
            cur.append(toks[i])
            i += 1
        if cur:
            parts.append(cur)
        return parts

    def _new_op_at(self, toks: list[str], j: int, cur: list[str]) -> list[str] | None:
        """Whether a new operation starts at j (after "and"): the words it starts with, else None."""
        # "make it stop and ..." keeps going; "... and delete the car" starts a new op
        if j < len(toks) and toks[j] in EDIT_VERBS and toks[j] != "show" and not (
                cur[0] in ("make", "let", "have") and toks[j] in MAKE_MOTION_VERBS and _make_has_no_complement(cur)):
            return []
        # gapping: "make the ball blue and the cube red"
        if cur[0] in GAPPING_VERBS and j < len(toks) and \
                toks[j] in DETS | {"it"} and any(match_color(cur, k) is not None for k in range(2, len(cur))):
            np_ = parse_np(toks, j, edit=True)
            if np_ is not None and np_.end < len(toks) and (match_color(toks, np_.end) is not None
                                                            or toks[np_.end] in ADDITIVE_COLORS):
                return [cur[0]]
        return None

    def _read_one(self, toks: list[str]) -> list[dict]:
        """The ops of one operation, read by the reader of its verb."""
        for axis_reader in AXIS_READERS.handlers_for(toks[0]):       # the perturbation axes' sentences first
            drafts = axis_reader(self, toks)
            if drafts is not None:
                return drafts
        reader = _VERB_READERS.get(toks[0])
        if reader is None:
            raise self.fail(f"'{toks[0]}' is not an edit this parser knows")
        return reader(self, toks[0], toks, toks[1:])

    # one reader per verb group (keys of lexicon.EDIT_VERB_GROUPS) -------------------------------------------
    def _camera_decl(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        return [self._camera_op(read_camera(rest))]

    def _make_verb(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        if w == "turn" and rest and rest[0] in ("the", "camera") and "camera" in rest[:2]:
            return [self._camera_op(read_camera(toks))]
        return self._make(rest, verb=w)

    def _paint(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        targets, k = self._targets(rest)
        tail = [x for x in rest[k:] if x not in PAINT_FILLERS]
        return [self._recolor(targets, tail, assign=True)]

    def _tint(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        targets, k = self._targets(rest)
        tail = [x for x in rest[k:] if x not in TINT_FILLERS]
        col = match_color(tail)
        if col is None:
            raise self.fail("expected a colour to tint with")
        return [self._additive(targets, col, 0.3)]

    def _change_verb(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        return self._change(rest)

    def _give(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        targets, k = self._targets(rest)
        tail = rest[k:]
        col = next((c for c in (match_color(tail, j) for j in range(len(tail))) if c is not None), None)
        if col is None:
            raise self.fail("expected 'give X a <colour> tint'")
        if any(x in ("tint", "hue", "shade", "touch") for x in tail):
            return [self._additive(targets, col, 0.3)]
        return [self._recolor(targets, [col[0]], assign=True)]

    def _add(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        """ "add some blue to X" (adding objects is not an edit)."""
        amount = 0.3
        j = 0
        while j < len(rest) and rest[j] in ("some", "a", "bit", "of", "little", "more", "touch", "hint", "lot",
                                            "alot", "much"):
            if rest[j] in ("bit", "little", "touch", "hint"):
                amount = 0.15
            if rest[j] in ("lot", "alot", "much"):
                amount = 0.5
            j += 1
        col = match_color(rest, j)
        if col is None:
            raise self.fail("adding objects is not supported in an edit (describe them when generating); "
                            "'add some blue to X' adds colour")
        k = j + col[2]
        while k < len(rest) and rest[k] in ("to", "onto", "on", "color", "tint"):
            k += 1
        targets, _ = self._targets(rest[k:])
        return [self._additive(targets, col, amount)]

    def _darken(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        targets, k = self._targets(rest)
        return [self._multiply(targets, DARKER.get(w, 0.6) * self._amount_mult(rest[k:]))]

    def _brighten(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        targets, _ = self._targets(rest)
        return [self._multiply(targets, BRIGHTER.get(w, 1.5))]

    def _redden(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        targets, _ = self._targets(rest)
        return [self._additive(targets, ("red", color_rgb("red"), 1), 0.3)]

    def _remove(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        if rest and rest[0] == "out":
            rest = rest[1:]
        targets, k = self._targets(rest)
        self._refuse_except(w, rest, k)
        self._no_leftover(rest[k:])
        return [{"op": "remove", "targets": targets}]

    def _refuse_except(self, w: str, rest: list[str], k: int) -> None:
        """ "delete everything except the bus": a remove that keeps something is an extract; say so."""
        tail = rest[k:]
        if tail and tail[0] in ("except", "but", "besides", "apart"):
            kept = [x for x in tail[1:] if x not in ("for", "from", "the", "a", "an")]
            keep = " ".join(kept) or "X"
            raise CommandError(f"Could not understand the edit {self.seg!r}: '{w} everything {tail[0]} ...' is not an "
                               f"edit of its own; to keep only the {keep} say 'extract the {keep}'")

    def _take(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        """ "take out the ball", "take the ball away"."""
        if not (rest and (rest[0] in ("out", "away") or rest[-1] in ("out", "away"))):
            raise self.fail(f"'{w}' is not an edit this parser knows")
        r = rest[1:] if rest[0] in ("out", "away") else rest[:-1]
        targets, k = self._targets(r)
        self._no_leftover(r[k:])
        return [{"op": "remove", "targets": targets}]

    def _extract(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        r = [x for x in rest if x not in ("out", "only", "just")]
        if w in ("keep", "show") and not (rest and rest[0] in ("only", "just")) and not (
                len(rest) > 1 and rest[-1] == "only"):
            if w == "keep" and rest:
                # "keep the ball moving" / "keep the camera still"
                return self._make(rest, verb="keep")
            raise self.fail(f"expected '{w} only X'")
        targets, k = self._targets(r)
        self._no_leftover(r[k:])
        return [{"op": "extract", "targets": targets}]

    def _reverse(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        r = [x for x in rest if x not in ("the", "direction", "directions", "motion", "movement", "of", "trajectory",
                                          "path", "course", "heading", "velocity", "'s")]
        if not r and rest:
            r = rest
        targets, k = self._targets(r or ["it"])
        self._no_leftover((r or ["it"])[k:])
        return [{"op": "reverse", "targets": targets}]

    def _stop(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        if "camera" in rest:
            return [self._camera_op({"motion": "fixed"})]
        r = [x for x in rest if x not in STOP_FILLERS] or ["it"]
        targets, _ = self._targets(rest if rest and rest[0] in DETS | PRONOUNS | {"all", "everything"} else r)
        return [{"op": "stop", "targets": targets}]

    def _speed(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        return [self._speed_verb(w, rest)]

    def _camera_verb(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        if w in ("orbit", "circle", "rotate") and rest and "camera" not in rest and not any(
                x in ("view", "viewpoint", "shot") for x in rest):
            # "circle the ball around the tree": a path change
            targets, k = self._targets(rest)
            return self._motion_ops(targets, ["circle"] + rest[k:], implied="circle")
        return [self._camera_op(read_camera(toks))]

    def _move(self, w: str, toks: list[str], rest: list[str]) -> list[dict]:
        if rest and "camera" in rest[:3]:
            return [self._camera_op(read_camera(toks))]
        if w in MOTION_VERBS_NEEDING_OBJECT and (not rest or rest[0] not in
                                                                                   DETS | PRONOUNS):
            raise self.fail(f"'{w}' needs an object: say which object should {w}")
        targets, k = self._targets(rest)
        implied = {"bounce": "bounce", "zigzag": "zigzag"}.get(w)
        return self._motion_ops(targets, rest[k:], implied=implied, verb=w)


def _make_has_no_complement(cur: list[str]) -> bool:
    np_ = parse_np(cur, 1, edit=True)
    return np_ is not None and np_.end >= len(cur)


_GROUP_READERS: dict[str, Reader] = {
    "camera_decl": EditReader._camera_decl, "make": EditReader._make_verb, "paint": EditReader._paint,
    "tint": EditReader._tint, "change": EditReader._change_verb, "give": EditReader._give, "add": EditReader._add,
    "darken": EditReader._darken, "brighten": EditReader._brighten, "redden": EditReader._redden,
    "remove": EditReader._remove, "take": EditReader._take, "extract": EditReader._extract,
    "reverse": EditReader._reverse, "stop": EditReader._stop, "speed": EditReader._speed,
    "camera": EditReader._camera_verb, "move": EditReader._move,
}
_VERB_READERS: dict[str, Reader] = {verb: _GROUP_READERS[group] for group, verbs in EDIT_VERB_GROUPS.items()
                                    for verb in verbs}
