"""The phrase scanner: reads verb, direction, path, speed and landmark phrases of a token span into a
`Predicate`.

Each construction is a small handler ``(scanner, i, pred) -> index after it, or None`` registered
in a `WordTable` with the words it can start with (or for any word: the handler then tests the word
itself). At each position the scanner tries, in registration order, the handlers of the word there
and takes the first that reads something; the last handler skips any word (noting it in
``pred.unknown`` when the parser does not know it).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..lexicon import (
    AUX,
    CLOCKWISE_WORDS,
    CONJ,
    DETS,
    DIRECTION_WORDS,
    FAR_WORDS,
    INTENSIFIERS,
    LOCATIVE_PREPS,
    OBJECT_STARTS,
    PATH_MODIFIERS,
    RELATIVE,
    RELATIVE_SPEED_STARTS,
    SIDE_STARTS,
    SPEED_PHRASES,
    SPEED_VERBS,
    STATIONARY,
    VERB_OBJECT_ROLES,
    VERBS,
    verb_info,
)
from ..vocabulary import noun_to_category, word_to_setting
from .dispatch import NUMBER, WordTable
from .motion import Predicate, direction_of, side_at
from .nouns import parse_np
from .speeds import relative_speed
from .tokens import known_word, match_phrase

__all__ = ["PhraseScanner"]

_TABLE = WordTable()  # handlers (scanner, i, pred) -> index after what they read, or None
_on, _any_word = _TABLE.on, _TABLE.any_word


class PhraseScanner:
    """Reads verb, direction, path, speed and landmark phrases from a token span."""

    def __init__(self, toks: Sequence[str], edit: bool = False) -> None:
        self.toks = toks
        self.edit = edit
        self.span: Sequence[str] = toks

    def scan(self, i: int, end: int, pred: Predicate, boundary: Any = None) -> int:
        """Read tokens i..end into `pred`, stopping early where `boundary(k)` is true; returns where
        it stopped."""
        self.span = self.toks[:end]
        while i < end:
            if boundary is not None and boundary(i):
                break
            for handler in _TABLE.handlers_for(self.span[i]):
                k = handler(self, i, pred)
                if k is not None:
                    i = k
                    break
        return i

    def next_word(self, i: int) -> str:
        """The word after i in the span, or ""."""
        return self.span[i + 1] if i + 1 < len(self.span) else ""

    def word_at(self, k: int) -> str:
        return self.span[k] if k < len(self.span) else ""


# -- speeds ---------------------------------------------------------------------------------------------


@_on(RELATIVE_SPEED_STARTS, NUMBER)
def _relative(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "twice as fast", "3 times faster", "50 percent slower", "faster"."""
    hit = relative_speed(sc.span, i)
    if hit is None:
        return None
    pred.factor = hit[0]
    return hit[1]


@_on({p[0] for p in SPEED_PHRASES})
def _speed_phrase(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "slowly", "at a crawl", "very fast" (longest first)."""
    sp = match_phrase(sc.span, i, SPEED_PHRASES)
    if sp is None:
        return None
    pred.speed, pred.speed_word = sp[0], " ".join(sc.span[i:i + sp[1]])
    return i + sp[1]


@_on("faster", "quicker", "slower", "speedier", "speed", "slow")
def _speed_up(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "speed up", "slow down"."""
    if sc.span[i] in ("speed", "slow") and sc.next_word(i) not in ("up", "down"):
        return None
    hit = relative_speed(sc.span, i, allow_bare=True)
    if hit is None:
        return None
    pred.factor = hit[0]
    return hit[1]


@_on("not", "never")
def _negation(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    pred.negated = True
    return i + 1


# -- sides and landmarks --------------------------------------------------------------------------------


@_on("from")
def _from(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "from the left", "from side to side", "from the tree", "from the camera"."""
    t = sc.span
    side = side_at(t, i + 1)
    if side is not None and sc.word_at(i + 1 + side[1]) != "of":
        pred.from_side = (direction_of(side[0]), " ".join(t[i:i + 1 + side[1]]))
        return i + 1 + side[1]
    if sc.next_word(i) == "side" and i + 3 < len(t) and t[i + 2] == "to" and t[i + 3] == "side":
        pred.oscillate, pred.oscillate_axis = True, (1.0, 0.0, 0.0)
        return i + 4
    np_ = parse_np(t, i + 1)
    if np_ is None:
        return i + 1
    if np_.kind in ("category", "unknown"):
        pred.start = np_
    elif np_.kind == "setting":
        pred.settings.append(np_.category)
    elif np_.kind == "viewer":
        pred.dirs.append((direction_of("away"), "from the camera"))
    else:
        return i + 1
    return np_.end


@_on(SIDE_STARTS)
def _side_to_side(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "left to right", "top to the bottom"."""
    t = sc.span
    side = side_at(t, i)
    if side is None or sc.word_at(i + side[1]) != "to":
        return None
    side2 = side_at(t, i + side[1] + 1)
    if side2 is None:
        return None
    pred.from_side = (direction_of(side[0]), t[i])
    pred.to_side = (direction_of(side2[0]), " ".join(t[i:i + side[1] + 1 + side2[1]]))
    return i + side[1] + 1 + side2[1]


@_on("to", "toward", "into", "onto")
def _to_each_other(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "towards each other": a relation between the subjects, not an object."""
    if sc.next_word(i) in ("each", "one") and sc.word_at(i + 2) in ("other", "another"):
        if sc.span[i] in ("to", "toward"):       # "toward(s) each other": the two subjects meet
            pred.mutual = True
        return i + 3
    return None


@_on("to", "toward", "into", "onto", "until", "reaching", "up")
def _to(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "to the left", "up to the tree", "to and fro", "into the sky", "towards the camera"."""
    t = sc.span
    w = t[i]
    if w == "up":
        if sc.next_word(i) != "to":
            return None
        i, w = i + 1, "to"
    j = i + 1
    if w == "to" and sc.word_at(j) in ("and", "fro") and (t[j] == "fro" or sc.word_at(j + 1) == "fro"):
        pred.oscillate = True
        return j + (1 if t[j] == "fro" else 2)
    side = side_at(t, j)
    if side is not None and w in ("to", "toward", "until", "reaching"):
        if pred.to_side is not None and pred.from_side is None:
            pred.from_side = pred.to_side  # "moves left to right": second side is the end
        if sc.word_at(j) == "sky" or sc.word_at(j + 1) == "sky":
            pred.settings.append("sky")
        pred.to_side = (direction_of(side[0]), " ".join(t[i:j + side[1]]))
        return j + side[1]
    return _to_landmark(sc, i, j, w, pred)


def _to_landmark(sc: PhraseScanner, i: int, j: int, w: str, pred: Predicate) -> int:
    np_ = parse_np(sc.span, j)
    if np_ is None:
        return i + 1
    words = " ".join(sc.span[i:np_.end])
    if np_.kind == "viewer":
        pred.dirs.append((direction_of("toward"), words))
    elif np_.head in FAR_WORDS:
        pred.dirs.append((direction_of("away"), words))
    elif np_.kind == "setting":
        pred.settings.append(np_.category)
        if np_.category == "sky" and w in ("into", "toward", "to"):
            pred.dirs.append((direction_of("up"), words))
    elif np_.kind in ("category", "unknown"):
        pred.end = np_
    elif np_.kind == "camera":
        pred.dirs.append((direction_of("toward"), words))
    else:
        return i + 1
    return np_.end


@_on("away")
def _away(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "away", "away from the camera", "away from the dog"."""
    if sc.next_word(i) == "from":
        np_ = parse_np(sc.span, i + 2)
        if np_ is not None and np_.kind in ("viewer", "camera"):
            pred.dirs.append((direction_of("away"), " ".join(sc.span[i:np_.end])))
            return np_.end
        if np_ is not None and np_.kind in ("category", "unknown"):
            pred.start = np_
            return np_.end
    pred.dirs.append((direction_of("away"), "away"))
    return i + 1


@_on("closer", "nearer")
def _closer_to(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "closer to the camera", "nearer to the tree"."""
    if sc.next_word(i) != "to":
        return None
    np_ = parse_np(sc.span, i + 2)
    if np_ is not None and np_.kind in ("viewer", "camera"):
        pred.dirs.append((direction_of("toward"), " ".join(sc.span[i:np_.end])))
        return np_.end
    if np_ is not None and np_.kind in ("category", "unknown"):
        pred.end = np_
        return np_.end
    return None


# -- paths ----------------------------------------------------------------------------------------------


@_on("around", "round", "in")
def _around(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "around the tree", "round and round", "around in circles", "in circles"."""
    t = sc.span
    w = t[i]
    if w == "in":
        if sc.next_word(i) not in ("circles", "circle", "loops", "loop", "a"):
            return None
        k = _path_phrase(t, i, pred)
        return i + k if k else None
    j = i + 1
    if sc.word_at(j) == "in":
        k = _path_phrase(t, j, pred)
        pred.path = pred.path or "circle"
        return i + 1 + k
    if sc.word_at(j) == "and" and sc.word_at(j + 1) in ("around", "round"):
        pred.path = "circle"
        return i + 3
    np_ = parse_np(t, j)
    pred.path = "circle"
    if np_ is not None and np_.kind in ("category", "unknown"):
        pred.around = np_
        return np_.end
    if np_ is not None and np_.kind in ("setting", "all"):
        if np_.kind == "setting":
            pred.settings.append(np_.category)
        return np_.end
    return i + 1


def _path_phrase(t: Sequence[str], i: int, pred: Predicate) -> int:
    """ "in a circle", "in circles", "in a loop", "in a zigzag (pattern)", "in a straight line":
    how many tokens it spans (0 if none)."""
    end = len(t)
    if t[i] != "in":
        return 0
    j = i + 1
    if j < end and t[j] == "a":
        j += 1
    while j < end and t[j] in PATH_MODIFIERS:
        j += 1
    if j >= end:
        return 0
    head = t[j]
    words = t[i + 1:j + 1]
    if head in ("circle", "circles", "loop", "loops", "ring") or (
            head in ("path", "motion", "pattern", "arc", "orbit") and "circular" in words):
        pred.path = "circle"
    elif head in ("zigzag", "zigzags") or (head in ("path", "pattern", "line", "motion") and "zigzag" in words):
        pred.path = "zigzag"
    elif head == "line" and "straight" in words:
        pred.path = pred.path or "straight"
    else:
        return 0
    j += 1
    if j < end and t[j] in ("pattern", "path", "motion", "line", "shape"):
        j += 1
    return j - i


@_on("in")
def _in_place(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    if sc.next_word(i) != "place":
        return None
    pred.in_place = True
    return i + 2


@_on("in")
def _in_path(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "in a zigzag", "in zigzags"."""
    if sc.next_word(i) not in ("a", "zigzags", "zigzag"):
        return None
    k = _path_phrase(sc.span, i, pred)
    return i + k if k else None


@_on("back")
def _back_and_forth(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    if sc.next_word(i) == "and" and sc.word_at(i + 2) in ("forth", "forward", "forwards"):
        pred.oscillate = True
        return i + 3
    return None


@_on("side")
def _side_to_side_oscillation(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    if sc.next_word(i) == "to" and sc.word_at(i + 2) == "side":
        pred.oscillate, pred.oscillate_axis = True, (1.0, 0.0, 0.0)
        return i + 3
    return None


@_on("up", "left")
def _up_and_down(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "up and down", "left and right"."""
    if sc.next_word(i) == "and" and sc.word_at(i + 2) in ("down", "right"):
        pred.oscillate = True
        pred.oscillate_axis = (0.0, 0.0, 1.0) if sc.span[i] == "up" else (1.0, 0.0, 0.0)
        return i + 3
    return None


@_on("backwards", "backward", "back")
def _backwards(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """In an edit, "backwards" reverses the motion."""
    if not sc.edit:
        return None
    pred.reverse = True
    return i + 1


@_on("opposite", "other")
def _opposite_way(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    if sc.next_word(i) not in ("way", "direction", "directions"):
        return None
    pred.reverse = True
    return i + 2


@_on(CLOCKWISE_WORDS)
def _clockwise(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    pred.clockwise = CLOCKWISE_WORDS[sc.span[i]]
    return i + 1


@_on("zigzag", "zigzags")
def _zigzag(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    if verb_info(sc.span[i]):
        return None
    pred.path = "zigzag"
    return i + 1


# -- directions and verbs -------------------------------------------------------------------------------


@_on("up", "down")
def _up_the(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "up the hill", "down the road": a place, not a direction word alone."""
    if sc.next_word(i) not in ("the", "a", "this", "that") or i + 2 >= len(sc.span):
        return None
    np_ = parse_np(sc.span, i + 1)
    if np_ is None or np_.kind not in ("setting", "category", "unknown"):
        return None
    if np_.kind == "setting":
        pred.settings.append(np_.category)
    elif np_.kind == "category":
        pred.statics.append(np_)
    return np_.end


@_on({w for w in DIRECTION_WORDS if w not in ("top", "bottom", "sky")})
def _direction(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    w = sc.span[i]
    if w == "right" and sc.next_word(i) in ("now", "away"):
        return i + 2
    pred.dirs.append((direction_of(DIRECTION_WORDS[w]), w))
    return i + 1


@_on(STATIONARY)
def _stationary(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    pred.stationary = True
    return i + 1


@_on(VERBS)
def _verb(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """A motion verb, and its direct object: "circles the tree", "chases the cat", "crosses the road"."""
    w = sc.span[i]
    base, kind = verb_info(w)  # type: ignore[misc]
    pred.verbs.append((base, kind))
    if base in SPEED_VERBS and pred.speed is None:
        pred.speed, pred.speed_word = SPEED_VERBS[base], w
    nxt = sc.next_word(i)
    if not (nxt and base in VERB_OBJECT_ROLES and (
            nxt in DETS or noun_to_category(nxt) is not None or word_to_setting(nxt) is not None)):
        return i + 1
    np_ = parse_np(sc.span, i + 1)
    if np_ is None:
        return i + 1
    if np_.kind == "setting":
        pred.settings.append(np_.category)
    elif np_.kind in ("category", "unknown"):
        role = VERB_OBJECT_ROLES[base]
        if role == "statics":
            pred.statics.append(np_)
        else:
            setattr(pred, role, np_)
    elif np_.kind in ("viewer", "camera") and base == "approach":
        pred.dirs.append((direction_of("toward"), " ".join(sc.span[i:np_.end])))
    return np_.end


_PLACE_LEADS = {("next", "to"): 2, ("in", "front"): 3, ("on", "top"): 3, ("out", "of"): 2}


@_on(LOCATIVE_PREPS, "with", "next", "in")
def _locative(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "on the table", "in front of the house", "next to a tree", "with a dog": settings and
    static objects."""
    t = sc.span
    w = t[i]
    j = i + _place_lead(sc, i)
    np_ = parse_np(t, j)
    if np_ is not None:
        pred.settings.extend(np_.settings)  # "a snowy field": the modifier is the more specific
        if np_.kind == "setting" or (np_.head == "table" and w != "with" and np_.count is None
                                     and np_.color is None):
            pred.settings.append(np_.category if np_.kind == "setting" else "table")
        elif np_.kind in ("category", "unknown") and not (np_.kind == "unknown" and w == "in"):
            pred.statics.append(np_)
            if w == "with":
                pred.with_nps.append(np_)
        return np_.end
    if w in ("on", "at", "in", "with") and j < len(t) and word_to_setting(t[j]):
        pred.settings.append(word_to_setting(t[j]))
        return j + 1
    return i + 1


def _place_lead(sc: PhraseScanner, i: int) -> int:
    """How many words lead to the place: 1 ("on"), 2 ("next to", "out of"), 3 ("in front of")."""
    k = _PLACE_LEADS.get((sc.span[i], sc.next_word(i)), 1)
    if k == 3 and sc.word_at(i + 2) != "of":
        return 1
    return k


@_any_word
def _setting_word(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    w = sc.span[i]
    s = word_to_setting(w)
    if s is None or noun_to_category(w) is not None:
        return None
    pred.settings.append(s)
    return i + 1


@_on("each", "one")
def _each_other(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """ "each other": a relation between the subjects, not an object."""
    return i + 2 if sc.next_word(i) in ("other", "another") else None


@_any_word
def _object(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """An object of some verb ("a dog fetches a ball"), in descriptions."""
    w = sc.span[i]
    if sc.edit or not (w in OBJECT_STARTS or noun_to_category(w)):
        return None
    np_ = parse_np(sc.span, i)
    if np_ is not None and np_.kind == "category" and np_.end > i:
        pred.statics.append(np_)
        return np_.end
    return None


@_on(AUX, INTENSIFIERS, RELATIVE, DETS, CONJ, ",")
def _filler(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    return i + 1


@_any_word
def _other_word(sc: PhraseScanner, i: int, pred: Predicate) -> int | None:
    """Anything else is skipped; a word the parser does not know is noted."""
    if not known_word(sc.span[i]):
        pred.unknown.append(sc.span[i])
    return i + 1
