"""Noun phrases: determiner, count, colour, size, speed and head noun; and where a new clause starts."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

from ..colors import match_color
from ..grounding import ALL_WORDS, CAMERA_WORDS
from ..lexicon import (
    AUX,
    COLLECTIVE_NOUNS,
    DETS,
    INTENSIFIERS,
    PRONOUNS,
    SEGMENT_PUNCT,
    SIZE_WORDS,
    SPEED_PHRASES,
    SPEED_WORDS_1,
    STATIONARY,
    VERBS,
    VIEWERS,
)
from ..vocabulary import CATEGORIES, noun_to_category, word_to_setting
from .tokens import NUMBER_PHRASES, SIZE_PHRASES, is_adverb, known_word, match_phrase, number_at, stop_word

__all__ = ["NounPhrase", "parse_np", "clause_boundary"]


@dataclass
class NounPhrase:
    start: int
    end: int
    words: list[str]
    det: str | None = None
    count: int | None = None
    collective: bool = False
    color: tuple[str, tuple[float, float, float]] | None = None
    size: str | None = None
    scale: float = 1.0
    speed: tuple[float, str] | None = None
    head: str = ""
    kind: str = "unknown"  # category | setting | unknown | pronoun | all | camera | viewer
    category: str | None = None
    plural: bool = False
    settings: list[str] = field(default_factory=list)

    @property
    def text(self) -> str:
        return " ".join(w for w in self.words if w != "'s")


def parse_np(toks: Sequence[str], i: int, edit: bool = False) -> NounPhrase | None:
    """A noun phrase starting at i, or None when none starts there."""
    n = len(toks)
    if i >= n:
        return None
    np_ = NounPhrase(start=i, end=i, words=[])
    j = i
    w = toks[j]
    if w in PRONOUNS and w not in ("both", "its", "their", "his", "her"):
        np_.kind, np_.head, np_.end, np_.words = "pronoun", w, j + 1, [w]
        np_.plural = w in ("them", "they", "themselves")
        return np_
    if w in ("its", "their") and (j + 1 >= n or stop_word(toks[j + 1]) or toks[j + 1] in (
            "motion", "movement", "direction", "speed", "color", "path", "trajectory")):
        np_.kind, np_.head, np_.end, np_.words = "pronoun", w, j + 1, [w]
        np_.plural = w == "their"
        return np_
    num = None
    if w in ("a", "an") and (j + 1 < n) and match_phrase(toks, j, NUMBER_PHRASES) is None:
        np_.det = w
        j += 1
    elif w in ("all", "both", "each", "every") and j + 1 < n and toks[j + 1] in ("of",):
        np_.det = w
        j += 2
        if j < n and toks[j] in ("the", "these", "those"):
            j += 1
    elif w in DETS and (w not in ("all", "every", "each", "both") or j + 1 < n):
        np_.det = w
        j += 1
    if np_.det == "both":
        np_.count = 2
    num = number_at(toks, j)
    if num is not None and not (j + num[1] < n and toks[j + num[1]] in ("times", "percent", "%")):
        np_.count, k = num
        j += k
    if j + 1 < n and toks[j] in COLLECTIVE_NOUNS and toks[j + 1] == "of":
        np_.collective = True
        j += 2
        if j < n and toks[j] in ("the",):
            j += 1
    start_words = j
    collected: list[int] = []
    known_head = False
    while j < n:
        w = toks[j]
        if w == ",":
            nxt = toks[j + 1] if j + 1 < n else ""
            if (collected and not known_head and nxt and not stop_word(nxt) and nxt not in DETS
                    and number_at(toks, j + 1) is None and "," not in nxt):
                j += 1
                continue
            break
        if collected and w in DETS and w not in ("all", "every", "each"):
            break  # an article starts the next phrase ("a retriever fetches a ball")
        if known_head:
            # after a known noun only another known noun continues the phrase ("table lamp")
            if noun_to_category(w) is None:
                break
        # colour, size and speed modifiers: only when more of the phrase follows
        col = match_color(toks, j)
        if col is not None:
            after = toks[j + col[2]] if j + col[2] < n else None
            if after is not None and (not stop_word(after) or (after == "," and not edit) or noun_to_category(after)
                                      or (word_to_setting(after) and np_.det is not None)) and after != "'s":
                np_.color = np_.color or (col[0], col[1])  # "tomato red": the first colour names it
                collected.extend(range(j, j + col[2]))
                j += col[2]
                continue
            if collected and (after is None or stop_word(after)):
                break  # "make the vehicle blue": a trailing colour is the complement, not the noun
        if w in INTENSIFIERS and j + 1 < n and (toks[j + 1] in SPEED_WORDS_1 or " ".join(toks[j:j + 2]) in SIZE_WORDS):
            pass  # "very small" / "very fast": let the phrase tables below see both words
        elif stop_word(w) and not (w in SPEED_WORDS_1 and j + 1 < n and not stop_word(toks[j + 1])) and not (
                (word_to_setting(w) or noun_to_category(w)) and (
                    (not collected and np_.det is not None)
                    or (collected and (j + 1 >= n or toks[j + 1] in VERBS or toks[j + 1] in AUX)))):
            # nouns that are also verbs: "the park", "a yellow taxi speeds"
            break
        sz = match_phrase(toks, j, SIZE_PHRASES)
        if sz is not None and j + sz[1] < n and (not stop_word(toks[j + sz[1]]) or toks[j + sz[1]] == ","):
            np_.size = sz[0]
            np_.scale = SIZE_WORDS[sz[0]]
            collected.extend(range(j, j + sz[1]))
            j += sz[1]
            continue
        sp = match_phrase(toks, j, SPEED_PHRASES)
        if sp is not None and j + sp[1] < n and not stop_word(toks[j + sp[1]]):
            np_.speed = (sp[0], " ".join(toks[j:j + sp[1]]))
            collected.extend(range(j, j + sp[1]))
            j += sp[1]
            continue
        if w in INTENSIFIERS:
            j += 1
            continue
        collected.append(j)
        if (noun_to_category(w) is not None or (edit and word_to_setting(w)) or w in CAMERA_WORDS
                or w in ALL_WORDS and w != "all"):
            known_head = True
        j += 1
    if not collected:
        if np_.det is not None and np_.count is not None and start_words == j:
            # "the two" / "both": a number used as a noun phrase
            pass
        return None
    # an unknown word ending in -s right after a noun is probably an unknown verb ("a sedan skids")
    unknown = [k for k in collected if not known_word(toks[k])]
    if len(collected) >= 2 and len(unknown) >= 2 and collected[-1] == unknown[-1] and toks[collected[-1]].endswith("s") \
            and not toks[collected[-1]].endswith("ss"):
        j = collected[-1]
        collected = collected[:-1]
    head_i = collected[-1]
    head = toks[head_i]
    np_.head = head
    np_.start, np_.end = i, head_i + 1
    np_.words = list(toks[i:head_i + 1])
    for k in collected[:-1]:
        s = word_to_setting(toks[k])
        if s is not None and noun_to_category(toks[k]) is None:
            np_.settings.append(s)
    hit = noun_to_category(head)
    if head in CAMERA_WORDS:
        np_.kind = "camera"
    elif head in VIEWERS or head in ("viewer", "camera"):
        np_.kind = "viewer"
    elif head in ALL_WORDS or (head == "scene") or (head == "all"):
        np_.kind = "all"
    elif hit is not None and (word_to_setting(head) is None or head == "table" or head in CATEGORIES):
        np_.kind, np_.category, np_.plural = "category", hit[0], hit[1]
    elif word_to_setting(head) is not None:
        np_.kind, np_.category = "setting", word_to_setting(head)
    elif head in ("object", "objects", "thing", "things", "item", "items", "everything", "stuff"):
        np_.kind = "all" if head in ("objects", "things", "items", "everything", "stuff") or np_.det in (
            "all", "every", "each") else "generic"
    else:
        np_.kind = "unknown"
        np_.plural = head.endswith("s") and not head.endswith("ss") and len(head) > 3
    if np_.kind == "category" and np_.det in ("all", "every", "each") and not np_.plural:
        np_.plural = np_.det != "each"
    return np_


def clause_boundary(toks: Sequence[str], k: int) -> bool:
    """Whether a new clause (with its own subject) starts at token k."""
    w = toks[k]
    if w in SEGMENT_PUNCT:
        return True
    if w not in ("and", ",", "while", "as", "whereas", "whilst", "but", "meanwhile", "plus"):
        return False
    if w == "as" and k + 2 < len(toks) and toks[k + 2] == "as":  # "as fast as"
        return False
    j = k + 1
    while j < len(toks) and toks[j] in ("and", ",", "then", "also", "meanwhile"):
        j += 1
    if j >= len(toks):
        return True
    if toks[j] in ("there",):
        return True
    np_ = parse_np(toks, j)
    if np_ is None:
        return False
    if np_.kind in ("viewer",) or (np_.kind == "setting" and toks[j] not in DETS):
        return False
    # a new subject is followed by a verb (or the end: "... and a plate")
    e = np_.end
    while e < len(toks) and (toks[e] in ("and", ",") or toks[e] in DETS):
        nxt = parse_np(toks, e + 1 if toks[e] in ("and", ",") else e)
        if nxt is None:
            break
        e = nxt.end
    if e >= len(toks) or toks[e] in SEGMENT_PUNCT:
        return w != "as"
    t = toks[e]
    return t in VERBS or t in AUX or t in STATIONARY or t == "," or is_adverb(t) or t in SPEED_WORDS_1
