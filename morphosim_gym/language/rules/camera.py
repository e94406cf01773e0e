"""Camera clauses: split them from a description, and read their motion, direction, speed and target."""

from __future__ import annotations

from typing import Sequence

from ..lexicon import (
    CAMERA_BOUNDARY,
    CAMERA_DOLLY,
    CAMERA_FIXED,
    CAMERA_ORBIT,
    CAMERA_PAN,
    CLOCKWISE_WORDS,
    SEGMENT_PUNCT,
    SPEED_PHRASES,
    verb_info,
)
from ..vocabulary import noun_to_category, word_to_setting
from .nouns import clause_boundary, parse_np
from .tokens import match_phrase

__all__ = ["extract_camera_clauses", "read_camera"]


def extract_camera_clauses(toks: list[str]) -> tuple[list[str], list[list[str]]]:
    """Split camera clauses ("while the camera circles the table", "with a static camera") from the rest."""
    spans: list[tuple[int, int]] = []
    n = len(toks)
    for i, w in enumerate(toks):
        if w not in ("camera", "cam") and not (w == "view" and i > 0 and toks[i - 1] in ("the", "a")):
            continue
        if i >= 1 and toks[i - 1] in ("the",) and i >= 2 and toks[i - 2] in ("toward", "to", "at", "from", "past",
                                                                            "of", "into", "by"):
            continue
        if i >= 1 and toks[i - 1] in ("toward", "to", "at", "from", "into"):
            continue
        if spans and spans[-1][0] <= i < spans[-1][1]:
            continue
        s = i
        while s > 0 and toks[s - 1] not in CAMERA_BOUNDARY and toks[s - 1] != "and" and not (
                verb_info(toks[s - 1]) and toks[s - 1] not in CAMERA_FIXED and toks[s - 1] not in CAMERA_ORBIT | CAMERA_PAN | CAMERA_DOLLY):
            if toks[s - 1] == "with":
                s -= 1
                break
            s -= 1
        if s > 0 and toks[s - 1] in CAMERA_BOUNDARY | {"and"}:
            s -= 1
        e = i + 1
        while e < n and toks[e] not in CAMERA_BOUNDARY and toks[e] not in SEGMENT_PUNCT:
            if toks[e] == "and" and e + 1 < n:
                nxt = parse_np(toks, e + 1)
                if nxt is not None and nxt.kind in ("category", "unknown") and clause_boundary(toks, e):
                    break
            e += 1
        spans.append((s, e))
    if not spans:
        return toks, []
    rest: list[str] = []
    cams: list[list[str]] = []
    last = 0
    for s, e in spans:
        rest.extend(toks[last:s])
        cams.append(toks[s:e])
        last = e
    rest.extend(toks[last:])
    while rest and rest[-1] in ("and", ",", "while", "as", "with"):
        rest.pop()
    return rest, cams


def read_camera(toks: Sequence[str]) -> dict:
    """Camera motion, direction, speed and target from a camera clause."""
    out: dict = {"motion": "fixed"}
    words = list(toks)
    motion = None
    direction = None
    target_np = None
    settings: list[str] = []
    i = 0
    n = len(words)
    while i < n:
        w = words[i]
        sp = match_phrase(words, i, SPEED_PHRASES)
        if sp is not None:
            out["speed"], out["speed_word"] = sp[0], " ".join(words[i:i + sp[1]])
            i += sp[1]
            continue
        if w in CLOCKWISE_WORDS:
            direction = "clockwise" if CLOCKWISE_WORDS[w] else "counterclockwise"
            motion = motion or "orbit"
            i += 1
            continue
        if w in CAMERA_ORBIT and w not in ("turns", "turn"):
            motion = "orbit"
            j = i + 1
            while j < n and words[j] in ("around", "round", "about", "slowly", "quickly", "all", "the", "way"):
                if words[j] in ("the", "all", "way"):
                    break
                j += 1
            np_ = parse_np(words, j) if j < n else None
            if np_ is not None and np_.kind in ("category", "unknown", "setting", "pronoun"):
                target_np = np_
                i = np_.end
                continue
            if np_ is not None:
                if np_.kind == "setting":
                    settings.append(np_.category)
                i = np_.end
                continue
            i += 1
            continue
        if w in CAMERA_PAN and motion != "orbit":
            motion = "pan"
            i += 1
            continue
        if w in ("zoom", "zooms", "zooming", "dolly", "dollies", "dollying", "push", "pushes", "pushing", "pull",
                 "pulls", "pulling", "closer", "nearer", "approaches", "approach", "approaching", "retreats",
                 "backs", "recedes") and motion != "orbit":
            motion = "dolly"
            if w in ("closer", "nearer", "approaches", "approach", "approaching"):
                direction = "in"
            elif w in ("retreats", "backs", "recedes"):
                direction = "out"
            i += 1
            continue
        if w in ("in", "forward", "forwards", "closer") and motion == "dolly":
            direction = "in"
            i += 1
            continue
        if w in ("out", "back", "backward", "backwards", "away") and motion == "dolly":
            direction = "out"
            i += 1
            continue
        if w in ("left", "right", "leftward", "rightward", "leftwards", "rightwards"):
            if motion in (None, "pan", "fixed"):
                motion = "pan"
                direction = "left" if w.startswith("left") else "right"
            i += 1
            continue
        if w in ("moves", "move", "moving", "goes", "go") and i + 1 < n and words[i + 1] in ("closer", "nearer", "in",
                                                                                              "forward", "toward"):
            motion, direction = "dolly", "in"
            i += 2
            continue
        if w in ("moves", "move", "moving", "goes", "go") and i + 1 < n and words[i + 1] in ("away", "back", "out",
                                                                                              "backward", "backwards"):
            motion, direction = "dolly", "out"
            i += 2
            continue
        if w in CAMERA_FIXED and motion is None:
            motion = "fixed"
            i += 1
            continue
        if w in ("not", "never") and i + 1 < n and words[i + 1] in ("move", "moves", "moving"):
            motion = "fixed"
            i += 2
            continue
        if w in ("on", "in", "across", "over", "above", "at", "inside") and i + 1 < n:
            np_ = parse_np(words, i + 1)
            if np_ is not None and (np_.kind == "setting" or np_.head == "table"):
                settings.extend(np_.settings)
                settings.append(np_.category if np_.kind == "setting" else "table")
                i = np_.end
                continue
        s = word_to_setting(w)
        if s is not None and noun_to_category(w) is None:
            settings.append(s)
        i += 1
    out["motion"] = motion or "fixed"
    if out["motion"] == "fixed":
        direction = None
        target_np = None
        out.pop("speed", None)
        out.pop("speed_word", None)
    if out["motion"] == "pan" and direction not in ("left", "right", None):
        direction = None
    out["direction"] = direction
    out["target_np"] = target_np
    out["settings"] = settings
    return out
