"""Target phrases of an edit: "the fish and seaweed", "it", "all the balls", "everything", "the camera"."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from ...errors import CommandError
from ...colors import match_color
from ..lexicon import (
    ADDITIVE_COLORS,
    ALL_TARGET_TAIL,
    BRIGHTER,
    DARKER,
    DEMONSTRATIVES,
    DETS,
    EDIT_VERBS,
    EVERYTHING_WORDS,
    OBJECT_PRONOUNS,
    PRONOUN_ATTRIBUTES,
    PRONOUNS,
    SCENE_WORDS,
)
from ..vocabulary import noun_to_category, singular
from .nouns import parse_np
from .tokens import stop_word

__all__ = ["TargetDraft", "read_targets", "POSITION_WORDS"]


@dataclass
class TargetDraft:
    """An edit target as written, before it is resolved against a scene or plan."""

    text: str
    kind: str  # noun | pronoun | all | camera
    noun: str = ""
    color: tuple[str, tuple[float, float, float]] | None = None
    plural: bool = False
    position: str | None = None  # "left", "right", "front", "back": which of several matches (see POSITION_WORDS)


# Position words before a target's noun ("the left ball") -> which of the matching objects, as the
# generation camera sees them at t = 0: leftmost / rightmost in the image, nearest / farthest.
POSITION_WORDS = {"left": "left", "leftmost": "left", "right": "right", "rightmost": "right", "front": "front",
                  "nearest": "front", "closest": "front", "near": "front", "back": "back", "farthest": "back",
                  "furthest": "back", "far": "back", "rear": "back"}




def read_targets(toks: Sequence[str], fail: Callable[[str], CommandError],
                 required: bool = True) -> tuple[list[TargetDraft], int]:
    """The targets at the start of `toks` and the index after them; a position word before a noun
    ("the left ball") is read off into the target's `position`.

    Raises:
        CommandError: (from `fail`) no target where one is `required`.
    """
    stripped, at = _strip_position(toks)
    if at is None:
        return _read_targets(toks, fail, required)
    out, k = _read_targets(stripped, fail, required)
    if at >= k:                                   # the targets ended before the position word
        return _read_targets(toks, fail, required)
    word = toks[at]
    for t in out:
        if t.kind == "noun":                      # the first noun target (a phrase has one position word)
            t.position = POSITION_WORDS[word]
            words = t.text.split()
            t.text = " ".join(words[:1] + [word] + words[1:] if words and words[0] in DETS else [word] + words)
            break
    return out, k + 1


def _strip_position(toks: Sequence[str]) -> tuple[list[str], int | None]:
    """The tokens without the first position word that stands before a noun or colour (first, or after
    a determiner), and its index (None: there is none)."""
    for i, w in enumerate(toks):
        if w not in POSITION_WORDS or i + 1 >= len(toks) or not (i == 0 or toks[i - 1] in DETS):
            continue
        if noun_to_category(toks[i + 1]) is not None or match_color(list(toks), i + 1) is not None:
            return list(toks[:i]) + list(toks[i + 1:]), i
    return list(toks), None


def _read_targets(toks: Sequence[str], fail: Callable[[str], CommandError],
                  required: bool = True) -> tuple[list[TargetDraft], int]:
    out: list[TargetDraft] = []
    i = 0
    n = len(toks)
    while i < n:
        w = toks[i]
        if (w in ("and", ",", "both", "also") and out) or w == "both":
            i += 1
            continue
        if _is_everything(toks, i):
            i = _everything(toks, i, out)
            if i < n and toks[i] in ("and", ","):
                continue
            break
        if w in ("the", "whole", "entire") and i + 1 < n and toks[i + 1] in SCENE_WORDS:
            j = i + 1
            while j < n and toks[j] in SCENE_WORDS:
                j += 1
            out.append(TargetDraft(text=" ".join(toks[i:j]), kind="all", noun="*"))
            i = j
            break
        if _is_pronoun_target(toks, i):
            i = _pronoun(toks, i, out)
            if i < n and toks[i] in ("and", ",") and i + 1 < n and (toks[i + 1] in DETS or toks[i + 1] in PRONOUNS):
                continue
            break
        i, more = _noun_target(toks, i, out)
        if not more:
            break
    if not out and required:
        raise fail("expected what to edit (e.g. 'the ball', 'it', 'everything')")
    return out, i


def _is_everything(toks: Sequence[str], i: int) -> bool:
    """ "everything", "all", "all objects", "all of them" (but not "all the balls")."""
    n = len(toks)
    w = toks[i]
    if w in EVERYTHING_WORDS:
        return True
    if w != "all" or not (i + 1 >= n or toks[i + 1] in ("objects", "things", "the", "of", "items", "and", ",")):
        return False
    return not (i + 2 < n and toks[i + 1] == "the" and toks[i + 2] not in ("objects", "things", "items", "scene"))


def _everything(toks: Sequence[str], i: int, out: list[TargetDraft]) -> int:
    j = i + 1
    while j < len(toks) and toks[j] in ALL_TARGET_TAIL:
        j += 1
    out.append(TargetDraft(text=" ".join(toks[i:j]), kind="all", noun="*"))
    return j


def _is_pronoun_target(toks: Sequence[str], i: int) -> bool:
    """ "it", "them", "its", or a demonstrative before what is changed ("this one", "that red")."""
    w = toks[i]
    if w in OBJECT_PRONOUNS:
        return True
    if w not in DEMONSTRATIVES:
        return False
    if i + 1 >= len(toks):
        return True
    nxt = toks[i + 1]
    return (stop_word(nxt) or nxt in PRONOUN_ATTRIBUTES or match_color(toks, i + 1) is not None
            or nxt in ADDITIVE_COLORS or nxt in DARKER or nxt in BRIGHTER)


def _pronoun(toks: Sequence[str], i: int, out: list[TargetDraft]) -> int:
    w = toks[i]
    j = i + 1
    if j < len(toks) and toks[j] in ("one", "ones"):
        j += 1
    out.append(TargetDraft(text=w, kind="pronoun", noun=w, plural=w in ("them", "they", "their")))
    if j < len(toks) and toks[j] == "'s":
        j += 1
    return j


def _noun_target(toks: Sequence[str], i: int, out: list[TargetDraft]) -> tuple[int, bool]:
    """A noun phrase target at i: (index after it, whether another target follows)."""
    n = len(toks)
    np_ = parse_np(toks, i, edit=True)
    if np_ is None:
        return i, False
    if np_.kind == "viewer":
        return i, False
    if np_.kind == "camera":
        out.append(TargetDraft(text=np_.text, kind="camera", noun="camera"))
    elif np_.kind == "all" or (np_.kind == "generic" and np_.det in ("all", "every", "each")):
        out.append(TargetDraft(text=np_.text, kind="all", noun="*"))
    elif np_.kind == "pronoun":
        out.append(TargetDraft(text=np_.text, kind="pronoun", noun=np_.head, plural=np_.plural))
    else:
        noun = singular(np_.head) if np_.plural or np_.kind == "unknown" else np_.head
        out.append(TargetDraft(text=np_.text, kind="noun", noun=noun, color=np_.color, plural=np_.plural))
    i = np_.end
    if i < n and toks[i] == "'s":
        return i + 1, False
    if i < n and toks[i] in ("and", ","):
        j = i + 1
        while j < n and toks[j] in ("and", ","):
            j += 1
        if j < n and _may_start_target(toks, j):
            nxt = parse_np(toks, j, edit=True)
            if nxt is not None and nxt.kind != "viewer":
                return j, True
    return i, False


def _may_start_target(toks: Sequence[str], j: int) -> bool:
    w = toks[j]
    return (w in DETS or w in PRONOUNS or noun_to_category(w) is not None
            or (w not in EDIT_VERBS and not stop_word(w) and match_color(toks, j) is None
                and w not in ADDITIVE_COLORS))
