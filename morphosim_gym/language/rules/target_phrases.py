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

__all__ = ["TargetDraft", "read_targets"]


@dataclass
class TargetDraft:
    """An edit target as written, before it is resolved against a scene or plan."""

    text: str
    kind: str  # noun | pronoun | all | camera
    noun: str = ""
    color: tuple[str, tuple[float, float, float]] | None = None
    plural: bool = False




def read_targets(toks: Sequence[str], fail: Callable[[str], CommandError],
                 required: bool = True) -> tuple[list[TargetDraft], int]:
    """The targets at the start of `toks` and the index after them.

    Raises:
        CommandError: (from `fail`) no target where one is `required`.
    """
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
