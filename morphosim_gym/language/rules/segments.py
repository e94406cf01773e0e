"""Segments: split a command at sentence ends and "then", and classify each as a description or an edit."""

from __future__ import annotations

from ...colors import match_color
from ..lexicon import (
    AUX,
    AXIS_WORDS,
    CONTINUATIONS,
    EDIT_VERBS,
    MODAL_FILLERS,
    MODALS,
    PREAMBLE_PHRASES,
    PREAMBLE_WORDS,
    SEGMENT_PUNCT,
    VERBS,
    verb_info,
)
from .camera import extract_camera_clauses
from .nouns import parse_np

__all__ = ["camera_decl_to_edit", "classify", "skip_preamble", "split_segments"]


def split_segments(toks: list[str]) -> list[list[str]]:
    """The command's segments: split at sentence ends, "then", "afterwards", "finally", "after that"."""
    segs: list[list[str]] = []
    cur: list[str] = []
    i = 0
    while i < len(toks):
        w = toks[i]
        brk = _segment_break(toks, i) if w in _BREAK_WORDS and (cur or w in SEGMENT_PUNCT) else 0
        if brk:
            _close_segment(cur, segs)
            cur = []
            i += brk
            continue
        cur.append(w)
        i += 1
    _close_segment(cur, segs)
    out = []
    for seg in segs:
        seg = [w for w in seg if w != ":"]
        while seg and seg[0] in (",", "and", "then", "so"):
            seg = seg[1:]
        if seg:
            out.append(seg)
    return out


_BREAK_WORDS = frozenset(SEGMENT_PUNCT) | {"then", "afterward", "finally", "lastly", "subsequently", "after", "next"}


def _segment_break(toks: list[str], i: int) -> int:
    """How many words a segment break at i takes (0: none); only called inside a segment, or at punctuation."""
    w = toks[i]
    nxt = toks[i + 1] if i + 1 < len(toks) else None
    if w in SEGMENT_PUNCT or w == "then" or w in ("afterward", "finally", "lastly", "subsequently"):
        return 1
    if (w == "after" and nxt in ("that", "this", "which")) or (w == "next" and nxt == ","):
        return 2
    return 0


def _close_segment(cur: list[str], segs: list[list[str]]) -> None:
    while cur and cur[-1] in ("and", ",", ":"):
        cur.pop()
    if cur:
        segs.append(cur)


def skip_preamble(toks: list[str]) -> list[str]:
    changed = True
    while changed and toks:
        changed = False
        for pat in PREAMBLE_PHRASES:
            if tuple(toks[:len(pat)]) == pat:
                toks = toks[len(pat):]
                changed = True
        if toks and toks[0] in PREAMBLE_WORDS and len(toks) > 1 and not (toks[0] == "next" and toks[1] == "to"):
            toks = toks[1:]
            changed = True
        if toks and toks[0] == ",":
            toks = toks[1:]
            changed = True
    if toks and toks[-1] in ("please",):
        toks = toks[:-1]
    return toks


def classify(seg: list[str], after_generate: bool) -> tuple[str, list[str]]:
    """ "generate", "edit" or "camera" (a camera-only description), and the segment to parse."""
    toks = skip_preamble(list(seg))
    if not toks:
        return "edit", seg
    w = toks[0]
    if (w in EDIT_VERBS or w in AXIS_WORDS["verbs"]) and not (w == "set" and len(toks) > 1 and toks[1] == "of"):
        # "move the ball left" is an edit; "circle" etc. as imperative verbs are edits too
        return "edit", toks
    if w in ("i", "we") and len(toks) > 2 and toks[1] in ("want", "would", "need", "wish"):
        return "edit", _wish_to_edit(toks)
    if after_generate and w in CONTINUATIONS:
        return "edit", [CONTINUATIONS[w], "it"] + toks[1:]
    edit = _modal_to_edit(toks, after_generate)
    if edit is not None:
        return "edit", edit
    if _describes_camera_only(toks):
        return "camera", toks
    return "generate", toks


def _wish_to_edit(toks: list[str]) -> list[str]:
    """ "i want the ball to be blue" -> "make the ball blue"."""
    k = 2
    while k < len(toks) and toks[k] in ("like", "to", "want"):
        k += 1
    rest = toks[k:]
    if "to" in rest:
        t = rest.index("to")
        return ["make"] + rest[:t] + [x for x in rest[t + 1:] if x != "be"]
    return ["make"] + rest


def _modal_to_edit(toks: list[str], after_generate: bool) -> list[str] | None:
    """ "the ball should be blue", "the bus is now yellow", "the car must move faster" -> a "make" edit."""
    for k in range(1, min(len(toks), 8)):
        t = toks[k]
        if t in MODALS:
            return _modal_complement(toks, k, after_generate)
        if t in VERBS or t in AUX:
            return None
    return None


def _modal_complement(toks: list[str], k: int, after_generate: bool) -> list[str] | None:
    t = toks[k]
    np_ = parse_np(toks, 0, edit=True)
    if np_ is None or np_.end != k and not (np_.end < k and toks[np_.end] in ("and", ",")):
        return None
    rest = toks[k + 1:]
    if t in ("is", "are") and not (rest and rest[0] in ("now", "to")):
        return None
    if t in ("turns", "becomes", "gets") and not after_generate and not (rest and (
            match_color(rest) is not None or rest[0] in ("darker", "brighter", "lighter"))):
        return None
    while rest and rest[0] in MODAL_FILLERS:
        if rest[0] in ("changed", "turned", "colored") and len(rest) > 1 and rest[1] in ("to", "into"):
            rest = rest[2:]
            continue
        rest = rest[1:]
    if t in ("has", "have") and toks[k + 1:k + 2] != ["to"]:
        return None
    if t == "turns" and rest and verb_info(rest[0]) is None and match_color(rest) is None and rest[0] not in (
            "darker", "brighter", "lighter", "around", "back"):
        return None
    return ["make"] + toks[:k] + rest


def _describes_camera_only(toks: list[str]) -> bool:
    """A description of the camera alone ("the camera orbits slowly")."""
    if not ("camera" in toks or "view" in toks and toks[0] in ("the", "view")):
        return False
    rest, spans = extract_camera_clauses(toks)
    indefinite = any(toks[i] in ("a", "an") and i + 1 < len(toks) for i in range(len(toks)))
    return bool(spans) and not indefinite and not any(
        _parse_np_kind(rest, i) in ("category", "unknown") for i in range(len(rest)))


def _parse_np_kind(toks: list[str], i: int) -> str | None:
    np_ = parse_np(toks, i)
    return np_.kind if np_ is not None else None


def camera_decl_to_edit(toks: list[str]) -> list[str]:
    return ["__camera__"] + toks
