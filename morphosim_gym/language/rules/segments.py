"""Segments: split a command at sentence ends and "then", and classify each as a description or an edit."""

from __future__ import annotations

from ..colors import match_color
from ..lexicon import (
    AUX,
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

__all__ = ["split_segments", "skip_preamble", "classify", "camera_decl_to_edit"]


def split_segments(toks: list[str]) -> list[list[str]]:
    segs: list[list[str]] = []
    cur: list[str] = []
    i = 0
    n = len(toks)
    while i < n:
        w = toks[i]
        brk = 0
        if w in SEGMENT_PUNCT:
            brk = 1
        elif w == "then" and cur:
            brk = 1
        elif w in ("afterward", "finally", "lastly", "subsequently") and cur:
            brk = 1
        elif w == "after" and i + 1 < n and toks[i + 1] in ("that", "this", "which") and cur:
            brk = 2
        elif w == "next" and i + 1 < n and toks[i + 1] == "," and cur:
            brk = 2
        if brk:
            while cur and cur[-1] in ("and", ",", ":"):
                cur.pop()
            if cur:
                segs.append(cur)
            cur = []
            i += brk
            continue
        cur.append(w)
        i += 1
    while cur and cur[-1] in ("and", ",", ":"):
        cur.pop()
    if cur:
        segs.append(cur)
    out = []
    for s in segs:
        s = [w for w in s if w not in (":",)]
        while s and s[0] in (",", "and", "then", "so"):
            s = s[1:]
        if s:
            out.append(s)
    return out


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
    if w in EDIT_VERBS and not (w == "set" and len(toks) > 1 and toks[1] == "of"):
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
