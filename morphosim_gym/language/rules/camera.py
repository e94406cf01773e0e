"""Camera clauses: split them from a description, and read their motion, direction, speed and target."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from ..lexicon import (
    CAMERA_BOUNDARY,
    CAMERA_DOLLY,
    CAMERA_DOLLY_IN,
    CAMERA_DOLLY_OUT,
    CAMERA_DOLLY_VERBS,
    CAMERA_FIXED,
    CAMERA_LANDMARK_PREPS,
    CAMERA_ORBIT,
    CAMERA_PAN,
    CAMERA_PLACE_PREPS,
    CLOCKWISE_WORDS,
    PAN_SIDES,
    SEGMENT_PUNCT,
    SPEED_PHRASES,
    verb_info,
)
from ..vocabulary import noun_to_category, word_to_setting
from .dispatch import WordTable
from .nouns import NounPhrase, clause_boundary, parse_np
from .tokens import match_phrase

__all__ = ["extract_camera_clauses", "read_camera"]


def extract_camera_clauses(toks: list[str]) -> tuple[list[str], list[list[str]]]:
    """Split camera clauses ("while the camera circles the table", "with a static camera") from the rest."""
    spans: list[tuple[int, int]] = []
    for i in range(len(toks)):
        if toks[i] in ("camera", "cam", "view") and _names_the_camera(toks, i) and not (
                spans and spans[-1][0] <= i < spans[-1][1]):
            spans.append((_clause_start(toks, i), _clause_end(toks, i)))
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


def _names_the_camera(toks: list[str], i: int) -> bool:
    """ "camera" / "the view" as the subject of a clause (not "towards the camera")."""
    w = toks[i]
    if w not in ("camera", "cam") and not (w == "view" and i > 0 and toks[i - 1] in ("the", "a")):
        return False
    if i >= 2 and toks[i - 1] == "the" and toks[i - 2] in CAMERA_LANDMARK_PREPS:
        return False
    return not (i >= 1 and toks[i - 1] in ("toward", "to", "at", "from", "into"))


def _clause_start(toks: list[str], i: int) -> int:
    """Back from the camera word to the clause's boundary ("while", ",", "and", "with", a non-camera verb)."""
    s = i
    while s > 0 and toks[s - 1] not in CAMERA_BOUNDARY and toks[s - 1] != "and" and not _other_verb(toks[s - 1]):
        if toks[s - 1] == "with":
            s -= 1
            break
        s -= 1
    if s > 0 and (toks[s - 1] in CAMERA_BOUNDARY or toks[s - 1] == "and"):
        s -= 1
    return s


def _other_verb(w: str) -> bool:
    """A verb that is no camera verb (it belongs to the clause before the camera's)."""
    return bool(verb_info(w)) and w not in CAMERA_FIXED and w not in CAMERA_ORBIT and w not in CAMERA_PAN \
        and w not in CAMERA_DOLLY


def _clause_end(toks: list[str], i: int) -> int:
    """On from the camera word to a boundary, or to "and" before a new subject with its verb."""
    n = len(toks)
    e = i + 1
    while e < n and toks[e] not in CAMERA_BOUNDARY and toks[e] not in SEGMENT_PUNCT:
        if toks[e] == "and" and e + 1 < n:
            nxt = parse_np(toks, e + 1)
            if nxt is not None and nxt.kind in ("category", "unknown") and clause_boundary(toks, e):
                break
        e += 1
    return e


@dataclass
class _CameraDraft:
    motion: str | None = None
    direction: str | None = None
    speed: tuple[float, str] | None = None  # (factor, words)
    target_np: NounPhrase | None = None
    settings: list[str] = field(default_factory=list)


def read_camera(toks: Sequence[str]) -> dict:
    """Camera motion, direction, speed and target from a camera clause (a `WordTable` of small
    readers keyed by the word each starts with)."""
    words = list(toks)
    cam = _CameraDraft()
    i = 0
    while i < len(words):
        for reader in _TABLE.handlers_for(words[i]):
            k = reader(words, i, cam)
            if k is not None:
                i = k
                break
    out: dict = {"motion": cam.motion or "fixed"}
    if cam.speed is not None and out["motion"] != "fixed":
        out["speed"], out["speed_word"] = cam.speed
    direction, target_np = cam.direction, cam.target_np
    if out["motion"] == "fixed":
        direction = target_np = None
    if out["motion"] == "pan" and direction not in ("left", "right", None):
        direction = None
    out["direction"] = direction
    out["target_np"] = target_np
    out["settings"] = cam.settings
    return out


_TABLE = WordTable()  # readers (words, i, draft) -> index after what they read, or None


@_TABLE.on({p[0] for p in SPEED_PHRASES})
def _speed(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    sp = match_phrase(words, i, SPEED_PHRASES)
    if sp is None:
        return None
    cam.speed = (sp[0], " ".join(words[i:i + sp[1]]))
    return i + sp[1]


@_TABLE.on(CLOCKWISE_WORDS)
def _clockwise(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    cam.direction = "clockwise" if CLOCKWISE_WORDS[words[i]] else "counterclockwise"
    cam.motion = cam.motion or "orbit"
    return i + 1


@_TABLE.on(set(CAMERA_ORBIT) - {"turns", "turn"})
def _orbit(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    """ "orbits (around) the table", "circles it", "rotates"."""
    cam.motion = "orbit"
    j = i + 1
    while j < len(words) and words[j] in ("around", "round", "about", "slowly", "quickly"):
        j += 1
    np_ = parse_np(words, j) if j < len(words) else None
    if np_ is None:
        return i + 1
    if np_.kind in ("category", "unknown", "setting", "pronoun"):
        cam.target_np = np_
    return np_.end


@_TABLE.on(CAMERA_PAN)
def _pan(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    if cam.motion == "orbit":
        return None
    cam.motion = "pan"
    return i + 1


@_TABLE.on(CAMERA_DOLLY_VERBS)
def _dolly(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    """ "zooms", "pushes", "approaches" (in), "retreats" (out)."""
    if cam.motion == "orbit":
        return None
    cam.motion = "dolly"
    w = words[i]
    if w in CAMERA_DOLLY_IN:
        cam.direction = "in"
    elif w in CAMERA_DOLLY_OUT:
        cam.direction = "out"
    return i + 1


@_TABLE.on("in", "forward", "forwards", "closer")
def _dolly_in(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    if cam.motion != "dolly":
        return None
    cam.direction = "in"
    return i + 1


@_TABLE.on("out", "back", "backward", "backwards", "away")
def _dolly_out(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    if cam.motion != "dolly":
        return None
    cam.direction = "out"
    return i + 1


@_TABLE.on(PAN_SIDES)
def _pan_side(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    if cam.motion in (None, "pan", "fixed"):
        cam.motion = "pan"
        cam.direction = "left" if words[i].startswith("left") else "right"
    return i + 1


@_TABLE.on("moves", "move", "moving", "goes", "go")
def _moves(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    """ "moves closer", "goes back": a dolly."""
    nxt = words[i + 1] if i + 1 < len(words) else ""
    if nxt in ("closer", "nearer", "in", "forward", "toward"):
        cam.motion, cam.direction = "dolly", "in"
    elif nxt in ("away", "back", "out", "backward", "backwards"):
        cam.motion, cam.direction = "dolly", "out"
    else:
        return None
    return i + 2


@_TABLE.on(CAMERA_FIXED)
def _fixed(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    if cam.motion is not None:
        return None
    cam.motion = "fixed"
    return i + 1


@_TABLE.on("not", "never")
def _not_moving(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    if not (i + 1 < len(words) and words[i + 1] in ("move", "moves", "moving")):
        return None
    cam.motion = "fixed"
    return i + 2


@_TABLE.on(CAMERA_PLACE_PREPS)
def _place(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    """ "on the table", "over the water": the setting."""
    np_ = parse_np(words, i + 1) if i + 1 < len(words) else None
    if np_ is None or not (np_.kind == "setting" or np_.head == "table"):
        return None
    cam.settings.extend(np_.settings)
    cam.settings.append(np_.category if np_.kind == "setting" else "table")
    return np_.end


@_TABLE.any_word
def _other_word(words: list[str], i: int, cam: _CameraDraft) -> int | None:
    w = words[i]
    s = word_to_setting(w)
    if s is not None and noun_to_category(w) is None:
        cam.settings.append(s)
    return i + 1
