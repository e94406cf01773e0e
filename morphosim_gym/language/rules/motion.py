"""Motion phrases: verbs, directions, sides, paths, speeds and landmarks of a clause (`Predicate`),
and how they combine into one motion."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

from ...errors import CommandError
from ..lexicon import (
    AUX,
    CLOCKWISE_WORDS,
    CONJ,
    DETS,
    DIRECTION_WORDS,
    DIRECTIONS,
    FAR_WORDS,
    INTENSIFIERS,
    LOCATIVE_PREPS,
    NUMBER_WORDS,
    RELATIVE,
    SIDE_TAIL,
    SIDE_WORDS,
    SPEED_PHRASES,
    SPEED_VERBS,
    STATIONARY,
    vec_norm,
    verb_info,
)
from ..vocabulary import noun_to_category, word_to_setting
from .nouns import NounPhrase, parse_np
from .tokens import detok, is_number, known_word, match_phrase, number_at

__all__ = ["Predicate", "side_at", "direction_of", "PhraseScanner", "merge_pred", "merge_motion",
            "combine_directions", "path_of"]


@dataclass
class Predicate:
    verbs: list[tuple[str, str]] = field(default_factory=list)  # (base, kind)
    dirs: list[tuple[tuple[float, float, float], str]] = field(default_factory=list)
    from_side: tuple[tuple[float, float, float], str] | None = None
    to_side: tuple[tuple[float, float, float], str] | None = None
    path: str | None = None
    clockwise: bool | None = None
    speed: float | None = None
    speed_word: str | None = None
    factor: float | None = None  # relative speed ("twice as fast"), edits
    start: NounPhrase | None = None
    end: NounPhrase | None = None
    around: NounPhrase | None = None
    statics: list[NounPhrase] = field(default_factory=list)
    settings: list[str] = field(default_factory=list)
    stationary: bool = False
    in_place: bool = False
    negated: bool = False
    oscillate_axis: tuple[float, float, float] | None = None
    oscillate: bool = False
    reverse: bool = False
    unknown: list[str] = field(default_factory=list)
    with_nps: list[NounPhrase] = field(default_factory=list)

    def has_motion(self) -> bool:
        return bool([v for v in self.verbs if v[1] != "aux"] or self.dirs or self.from_side or self.to_side
                    or self.path or self.clockwise is not None or self.speed is not None or self.end
                    or self.start or self.around or self.stationary or self.oscillate)


def side_at(toks: Sequence[str], i: int) -> tuple[str, int] | None:
    """A side such as "left", "the left", "the left side", "the top of the screen" at i."""
    j = i
    n = len(toks)
    if j < n and toks[j] == "the":
        j += 1
    if j < n and toks[j] in ("far", "very"):
        j += 1
    if j >= n or toks[j] not in SIDE_WORDS:
        return None
    if toks[j] in ("sky", "ground") and j == i:  # "to sky" is not a side; "to the sky"/"to the ground" is
        return None
    side = SIDE_WORDS[toks[j]]
    j += 1
    while j < n and toks[j] in SIDE_TAIL | {"the", "screen", "frame", "image", "scene", "view"} and toks[j] != "to":
        if toks[j] == "of" and not (j + 1 < n and toks[j + 1] in ("the", "screen", "frame", "image", "scene", "view")):
            break
        j += 1
    return side, j - i


def direction_of(name: str) -> tuple[float, float, float]:
    return DIRECTIONS[name]


class PhraseScanner:
    """Reads verb, direction, path, speed and landmark phrases from a token span."""

    def __init__(self, toks: Sequence[str], edit: bool = False) -> None:
        self.toks = toks
        self.edit = edit

    def scan(self, i: int, end: int, pred: Predicate, boundary: Any = None) -> int:
        toks = self.toks
        while i < end:
            if boundary is not None and boundary(i):
                break
            w = toks[i]
            nxt = toks[i + 1] if i + 1 < end else ""
            # speed phrases (longest first), "twice as fast", "N times faster"
            k = self._relative_speed(i, end, pred)
            if k:
                i += k
                continue
            sp = match_phrase(toks[:end], i, SPEED_PHRASES)
            if sp is not None:
                pred.speed, pred.speed_word = sp[0], " ".join(toks[i:i + sp[1]])
                i += sp[1]
                continue
            if w in ("faster", "quicker", "slower", "speedier") or (w in ("speed", "slow") and nxt in ("up", "down")):
                k = self._relative_speed(i, end, pred, allow_bare=True)
                if k:
                    i += k
                    continue
            if w == "not" or (w in ("never",)):
                pred.negated = True
                i += 1
                continue
            # sides: "from left to right", "left to right", "from the left", "to the left"
            if w == "from":
                side = side_at(toks[:end], i + 1)
                if side is not None and not (i + 1 + side[1] < end and toks[i + 1 + side[1]] == "of"):
                    pred.from_side = (direction_of(side[0]), " ".join(toks[i:i + 1 + side[1]]))
                    i += 1 + side[1]
                    continue
                if nxt in ("side",) and i + 3 < end and toks[i + 2] == "to" and toks[i + 3] == "side":
                    pred.oscillate, pred.oscillate_axis = True, (1.0, 0.0, 0.0)
                    i += 4
                    continue
                np_ = parse_np(toks[:end], i + 1)
                if np_ is not None and np_.kind in ("category", "unknown"):
                    pred.start = np_
                    i = np_.end
                    continue
                if np_ is not None and np_.kind == "setting":
                    pred.settings.append(np_.category)
                    i = np_.end
                    continue
                if np_ is not None and np_.kind == "viewer":
                    pred.dirs.append((direction_of("away"), "from the camera"))
                    i = np_.end
                    continue
                i += 1
                continue
            side = side_at(toks[:end], i)
            if side is not None and w != "the" and i + side[1] < end and toks[i + side[1]] == "to" and w in (
                    "left", "right", "top", "bottom", "north", "south", "east", "west"):
                side2 = side_at(toks[:end], i + side[1] + 1)
                if side2 is not None:
                    pred.from_side = (direction_of(side[0]), w)
                    pred.to_side = (direction_of(side2[0]), " ".join(toks[i:i + side[1] + 1 + side2[1]]))
                    i += side[1] + 1 + side2[1]
                    continue
            if w in ("to", "toward", "into", "onto") and nxt in ("each", "one") and i + 2 < end and toks[i + 2] in (
                    "other", "another"):
                i += 3
                continue
            if w in ("to", "toward", "into", "onto", "until", "reaching") or (w == "up" and nxt == "to"):
                if w == "up":
                    i += 1
                    w = "to"
                    nxt = toks[i + 1] if i + 1 < end else ""
                j = i + 1
                if j < end and toks[j] in ("and", "fro") and w == "to":
                    if toks[j] == "fro" or (j + 1 < end and toks[j + 1] == "fro"):
                        pred.oscillate = True
                        i = j + (1 if toks[j] == "fro" else 2)
                        continue
                side = side_at(toks[:end], j)
                if side is not None and w in ("to", "toward", "until", "reaching"):
                    if pred.to_side is not None and pred.from_side is None:
                        pred.from_side = pred.to_side  # "moves left to right": second side is the end
                    if toks[j] in ("sky",) or (j + 1 < end and toks[j + 1] in ("sky",)):
                        pred.settings.append("sky")
                    pred.to_side = (direction_of(side[0]), " ".join(toks[i:j + side[1]]))
                    i = j + side[1]
                    continue
                np_ = parse_np(toks[:end], j)
                if np_ is not None and np_.kind == "viewer":
                    pred.dirs.append((direction_of("toward"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                if np_ is not None and np_.head in FAR_WORDS:
                    pred.dirs.append((direction_of("away"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                if np_ is not None and np_.kind == "setting":
                    pred.settings.append(np_.category)
                    if np_.category == "sky" and w in ("into", "toward", "to"):
                        pred.dirs.append((direction_of("up"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                if np_ is not None and np_.kind in ("category", "unknown"):
                    pred.end = np_
                    i = np_.end
                    continue
                if np_ is not None and np_.kind == "camera":
                    pred.dirs.append((direction_of("toward"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                i += 1
                continue
            if w == "away":
                j = i + 1
                if j < end and toks[j] == "from":
                    np_ = parse_np(toks[:end], j + 1)
                    if np_ is not None and np_.kind in ("viewer", "camera"):
                        pred.dirs.append((direction_of("away"), " ".join(toks[i:np_.end])))
                        i = np_.end
                        continue
                    if np_ is not None and np_.kind in ("category", "unknown"):
                        pred.start = np_
                        i = np_.end
                        continue
                pred.dirs.append((direction_of("away"), "away"))
                i += 1
                continue
            if w in ("closer", "nearer") and nxt == "to":
                np_ = parse_np(toks[:end], i + 2)
                if np_ is not None and np_.kind in ("viewer", "camera"):
                    pred.dirs.append((direction_of("toward"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                if np_ is not None and np_.kind in ("category", "unknown"):
                    pred.end = np_
                    i = np_.end
                    continue
            if w in ("around", "round") or (w == "in" and nxt in ("circles", "circle", "loops", "loop", "a")):
                k = self._around(i, end, pred)
                if k:
                    i += k
                    continue
            if w == "in" and nxt in ("place",):
                pred.in_place = True
                i += 2
                continue
            if w == "in" and nxt in ("a", "zigzags", "zigzag") and self._path_phrase(i, end, pred):
                i += self._path_phrase(i, end, pred)
                continue
            if w == "back" and nxt == "and" and i + 2 < end and toks[i + 2] in ("forth", "forward", "forwards"):
                pred.oscillate = True
                i += 3
                continue
            if w == "side" and nxt == "to" and i + 2 < end and toks[i + 2] == "side":
                pred.oscillate, pred.oscillate_axis = True, (1.0, 0.0, 0.0)
                i += 3
                continue
            if w in ("up", "left") and nxt == "and" and i + 2 < end and toks[i + 2] in ("down", "right"):
                pred.oscillate = True
                pred.oscillate_axis = (0.0, 0.0, 1.0) if w == "up" else (1.0, 0.0, 0.0)
                i += 3
                continue
            if w in ("backwards", "backward", "back") and self.edit:
                pred.reverse = True
                i += 1
                continue
            if w in ("opposite", "other") and nxt in ("way", "direction", "directions"):
                pred.reverse = True
                i += 2
                continue
            if w in CLOCKWISE_WORDS:
                pred.clockwise = CLOCKWISE_WORDS[w]
                i += 1
                continue
            if w in ("zigzag", "zigzags") and not verb_info(w):
                pred.path = "zigzag"
                i += 1
                continue
            if w in ("up", "down") and nxt in ("the", "a", "this", "that") and i + 2 < end:
                np_ = parse_np(toks[:end], i + 1)
                if np_ is not None and np_.kind in ("setting", "category", "unknown"):
                    if np_.kind == "setting":
                        pred.settings.append(np_.category)
                    elif np_.kind == "category":
                        pred.statics.append(np_)
                    i = np_.end
                    continue
            if w in DIRECTION_WORDS and w not in ("top", "bottom", "sky", "closer", "nearer") or w in (
                    "closer", "nearer"):
                if w in ("right",) and nxt in ("now", "away"):
                    i += 2
                    continue
                pred.dirs.append((direction_of(DIRECTION_WORDS[w]), w))
                i += 1
                continue
            if w in STATIONARY:
                pred.stationary = True
                i += 1
                continue
            vi = verb_info(w)
            if vi is not None:
                base, kind = vi
                pred.verbs.append((base, kind))
                if base in SPEED_VERBS and pred.speed is None:
                    pred.speed, pred.speed_word = SPEED_VERBS[base], w
                # direct objects: "circles the tree", "chases the cat", "crosses the road"
                if nxt and (nxt in DETS or noun_to_category(nxt) is not None or word_to_setting(nxt) is not None) \
                        and base in ("circle", "orbit", "chase", "follow", "approach", "reach", "leave", "cross",
                                     "pass", "traverse", "enter", "revolve", "loop", "climb", "descend"):
                    np_ = parse_np(toks[:end], i + 1)
                    if np_ is not None:
                        if np_.kind == "setting":
                            pred.settings.append(np_.category)
                        elif np_.kind in ("category", "unknown"):
                            if base in ("circle", "orbit", "revolve", "loop"):
                                pred.around = np_
                            elif base in ("chase", "follow", "approach", "reach"):
                                pred.end = np_
                            elif base == "leave":
                                pred.start = np_
                            else:
                                pred.statics.append(np_)
                        elif np_.kind in ("viewer", "camera") and base == "approach":
                            pred.dirs.append((direction_of("toward"), " ".join(toks[i:np_.end])))
                        i = np_.end
                        continue
                i += 1
                continue
            if w in LOCATIVE_PREPS or w == "with" or w == "next" or w == "in":
                j = i + 1
                if w == "next" and nxt == "to":
                    j = i + 2
                elif w == "in" and nxt == "front" and i + 2 < end and toks[i + 2] == "of":
                    j = i + 3
                elif w == "on" and nxt == "top" and i + 2 < end and toks[i + 2] == "of":
                    j = i + 3
                elif w == "out" and nxt == "of":
                    j = i + 2
                np_ = parse_np(toks[:end], j)
                if np_ is not None:
                    pred.settings.extend(np_.settings)  # "a snowy field": the modifier is the more specific
                    if np_.kind == "setting" or (np_.head == "table" and w != "with" and np_.count is None
                                                 and np_.color is None):
                        pred.settings.append(np_.category if np_.kind == "setting" else "table")
                    elif np_.kind in ("category", "unknown") and not (np_.kind == "unknown" and w == "in"):
                        pred.statics.append(np_)
                        if w == "with":
                            pred.with_nps.append(np_)
                    i = np_.end
                    continue
                if w in ("on", "at", "in", "with") and j < end and word_to_setting(toks[j]):
                    pred.settings.append(word_to_setting(toks[j]))
                    i = j + 1
                    continue
                i += 1
                continue
            s = word_to_setting(w)
            if s is not None and noun_to_category(w) is None:
                pred.settings.append(s)
                i += 1
                continue
            if w in ("each", "one") and nxt in ("other", "another"):
                i += 2  # "towards each other": a relation between the subjects, not an object
                continue
            if (w in ("a", "an", "the", "two", "three", "some") or noun_to_category(w)) and not self.edit:
                np_ = parse_np(toks[:end], i)  # an object of some verb ("a dog fetches a ball")
                if np_ is not None and np_.kind == "category" and np_.end > i:
                    pred.statics.append(np_)
                    i = np_.end
                    continue
            if w in AUX or w in INTENSIFIERS or w in RELATIVE or w in DETS or w in CONJ or w == ",":
                i += 1
                continue
            if not known_word(w):
                pred.unknown.append(w)
            i += 1
        return i

    def _relative_speed(self, i: int, end: int, pred: Predicate, allow_bare: bool = False) -> int:
        """ "twice as fast", "half as fast", "3 times faster", "50 percent slower", "faster"..."""
        toks = self.toks
        w = toks[i]
        j = i
        factor: float | None = None
        if w in ("minus", "negative") and j + 1 < end and (is_number(toks[j + 1]) or toks[j + 1] in NUMBER_WORDS):
            raise CommandError(f"Could not use a negative speed factor in {' '.join(toks[i:end])!r}: the factor "
                               f"must be > 0 (say 'reverse' to reverse a motion)")
        if w in ("twice", "double") and j + 2 < end and toks[j + 1] == "as" and toks[j + 2] in ("slow", "slowly"):
            factor, j = 0.5, j + 3  # "twice as slowly"
        elif w in ("twice", "double") and j + 2 < end and toks[j + 1] == "as" and toks[j + 2] in (
                "fast", "quickly", "quick", "rapidly"):
            factor, j = 2.0, j + 3
        elif w == "half" and j + 2 < end and toks[j + 1] == "as" and toks[j + 2] in ("fast", "quickly", "quick"):
            factor, j = 0.5, j + 3
        elif w in ("at", "to") and j + 2 < end and toks[j + 1] in ("half", "double", "twice", "triple") and toks[
                j + 2] in ("speed", "the"):
            factor = {"half": 0.5, "double": 2.0, "twice": 2.0, "triple": 3.0}[toks[j + 1]]
            j += 3
            if toks[j - 1] == "the" and j < end and toks[j] == "speed":
                j += 1
        elif w in ("half", "double", "triple") and j + 1 < end and toks[j + 1] in ("speed", "pace"):
            factor, j = {"half": 0.5, "double": 2.0, "triple": 3.0}[w], j + 2
        else:
            num = number_at(toks[:end], j) if (is_number(w) or w in NUMBER_WORDS) else None
            if num is not None and j + num[1] < end and toks[j + num[1]] in ("times", "percent"):
                value, k = num
                unit = toks[j + k]
                j2 = j + k + 1
                if j2 < end and toks[j2] == "as" and j2 + 1 < end and toks[j2 + 1] in ("fast", "quickly", "quick",
                                                                                     "slow", "slowly"):
                    slow = toks[j2 + 1] in ("slow", "slowly")
                    j2 += 2
                    if j2 < end and toks[j2] == "as":
                        j2 += 1
                elif j2 < end and toks[j2] in ("faster", "quicker", "slower", "more"):
                    slow = toks[j2] == "slower"
                    j2 += 1
                    if toks[j2 - 1] == "more" and j2 < end and toks[j2] in ("slowly", "quickly"):
                        slow = toks[j2] == "slowly"
                        j2 += 1
                elif unit == "times" and j2 < end and toks[j2] in ("the", "normal", "its", "their", "speed"):
                    slow = False
                    while j2 < end and toks[j2] in ("the", "normal", "its", "their", "original", "speed", "current"):
                        j2 += 1
                else:
                    return 0
                if unit == "percent":
                    factor = 1.0 + value / 100.0 * (-1 if slow else 1)
                else:
                    if value == 0:
                        factor = 0.0
                    else:
                        factor = 1.0 / value if slow else float(value)
                j = j2
            elif allow_bare or w in ("faster", "quicker", "slower", "speedier"):
                mod = 1.0
                if i >= 1 and toks[i - 1] in ("much", "alot", "far", "way", "lot"):
                    mod = 2.0
                elif i >= 1 and toks[i - 1] in ("bit", "little", "slightly", "somewhat", "tad"):
                    mod = 0.5
                if w in ("faster", "quicker", "speedier") or (w == "speed" and j + 1 < end and toks[j + 1] == "up"):
                    factor = {1.0: 2.0, 2.0: 3.0, 0.5: 1.25}[mod]
                elif w == "slower" or (w == "slow" and j + 1 < end and toks[j + 1] == "down"):
                    factor = {1.0: 0.5, 2.0: round(1 / 3, 6), 0.5: 0.8}[mod]
                else:
                    return 0
                j += 2 if w in ("speed", "slow") else 1
                if j < end and toks[j] == "than" and j + 1 < end:  # "faster than before/now"
                    j += 2
            else:
                return 0
        if factor is None:
            return 0
        if factor <= 0:
            raise CommandError(f"Could not use the speed change {' '.join(toks[i:j])!r}: the speed factor must be "
                               f"> 0 (say 'stop' to stop a motion)")
        pred.factor = round(factor, 6)
        return j - i

    def _around(self, i: int, end: int, pred: Predicate) -> int:
        toks = self.toks
        w = toks[i]
        if w in ("around", "round"):
            j = i + 1
            if j < end and toks[j] in ("in",):
                k = self._path_phrase(j, end, pred)
                pred.path = pred.path or "circle"
                return 1 + k
            if j < end and toks[j] in ("and",) and j + 1 < end and toks[j + 1] in ("around", "round"):
                pred.path = "circle"
                return 3
            np_ = parse_np(toks[:end], j)
            if np_ is not None and np_.kind in ("category", "unknown"):
                pred.around = np_
                pred.path = "circle"
                return np_.end - i
            if np_ is not None and np_.kind in ("setting", "all"):
                if np_.kind == "setting":
                    pred.settings.append(np_.category)
                pred.path = "circle"
                return np_.end - i
            pred.path = "circle"
            return 1
        return self._path_phrase(i, end, pred)

    def _path_phrase(self, i: int, end: int, pred: Predicate) -> int:
        """ "in a circle", "in circles", "in a loop", "in a zigzag (pattern)", "in a straight line" """
        toks = self.toks
        if toks[i] != "in":
            return 0
        j = i + 1
        if j < end and toks[j] == "a":
            j += 1
        while j < end and toks[j] in ("big", "large", "small", "wide", "tight", "little", "circular", "straight",
                                      "zigzag", "wavy", "round"):
            j += 1
        if j >= end:
            return 0
        head = toks[j]
        words = toks[i + 1:j + 1]
        if head in ("circle", "circles", "loop", "loops", "ring") or (head in ("path", "motion", "pattern", "arc",
                                                                             "orbit") and "circular" in words):
            pred.path = "circle"
        elif head in ("zigzag", "zigzags") or (head in ("path", "pattern", "line", "motion") and "zigzag" in words):
            pred.path = "zigzag"
        elif head == "line" and "straight" in words:
            pred.path = pred.path or "straight"
        else:
            return 0
        j += 1
        if j < end and toks[j] in ("pattern", "path", "motion", "line", "shape"):
            j += 1
        return j - i


def merge_pred(dst: Predicate, src: Predicate) -> Predicate:
    """Fill what `dst` lacks from `src` (a phrase fronted before its subject)."""
    dst.verbs += src.verbs
    dst.dirs += src.dirs
    for k in ("from_side", "to_side", "path", "clockwise", "speed", "speed_word", "factor", "start", "end", "around",
              "oscillate_axis"):
        if getattr(dst, k) is None:
            setattr(dst, k, getattr(src, k))
    dst.statics += src.statics
    dst.settings += src.settings
    dst.stationary = dst.stationary or src.stationary
    dst.oscillate = dst.oscillate or src.oscillate
    return dst


def merge_motion(old: dict, new: dict) -> dict:
    out = dict(old)
    for k, v in new.items():
        if k == "path":
            if v != "straight" or old["path"] == "stop":
                out[k] = v
        elif k == "speed":
            if new.get("speed_word") is not None:
                out[k] = v
        elif v is not None:
            out[k] = v
    if out["path"] != "circle":
        out["clockwise"] = None
        out["around"] = None
    if out["path"] == "stop":
        out["direction_world"] = None
        out["end"] = None
    return out


def combine_directions(pred: Predicate, toks: Sequence[str]) -> tuple[float, float, float] | None:
    parts: list[tuple[tuple[float, float, float], str]] = []
    if pred.from_side is not None and pred.to_side is not None:
        a, b = pred.from_side, pred.to_side
        v = vec_norm(tuple(y - x for x, y in zip(a[0], b[0])))
        if v is None or a[0] == b[0]:
            raise CommandError(f"Could not understand the direction in {detok(toks)!r}: it goes from {a[1]!r} to "
                               f"{b[1]!r}, which is the same place; say e.g. 'from left to right'")
        parts.append((v, f"{a[1]} {b[1]}"))
    elif pred.from_side is not None:
        parts.append((tuple(-c + 0.0 for c in pred.from_side[0]), pred.from_side[1]))  # type: ignore[misc]
    elif pred.to_side is not None:
        parts.append(pred.to_side)
    parts.extend(pred.dirs)
    for base, kind in pred.verbs:
        if kind in ("up", "down"):
            parts.append((direction_of(kind), base))
    if pred.oscillate and pred.oscillate_axis is not None:
        if pred.oscillate_axis == (0.0, 0.0, 1.0) and any(k == "bounce" for _, k in pred.verbs):
            return None  # "bounces up and down": a bounce in place
        return pred.oscillate_axis
    if not parts:
        return None
    for x in range(len(parts)):
        for y in range(x + 1, len(parts)):
            dot = sum(a * b for a, b in zip(parts[x][0], parts[y][0]))
            if dot < -0.5:
                raise CommandError(f"Could not understand the direction in {detok(toks)!r}: {parts[x][1]!r} and "
                                   f"{parts[y][1]!r} contradict each other; give one direction")
    uniq: list[tuple[float, float, float]] = []
    for v, _ in parts:
        if v not in uniq:
            uniq.append(v)
    total = vec_norm(tuple(sum(v[i] for v in uniq) for i in range(3)))
    return total


def path_of(pred: Predicate, direction: Any) -> str:
    kinds = [k for _, k in pred.verbs]
    if pred.negated and (kinds or pred.dirs) and not pred.path:
        return "stop"
    if pred.path is not None:
        return pred.path
    if pred.clockwise is not None or pred.around is not None:
        return "circle"
    if pred.oscillate:
        return "bounce" if "bounce" in kinds and pred.oscillate_axis == (0.0, 0.0, 1.0) else "oscillate"
    for k in ("zigzag", "circle", "bounce", "oscillate"):
        if k in kinds:
            return k
    moving = any(k in ("move", "up", "down") for k in kinds)
    if (pred.stationary or "stop" in kinds) and not moving:
        if direction is not None or pred.end is not None:
            raise CommandError("Could not understand a motion that is both still and moving: give one")
        return "stop"
    return "straight"
