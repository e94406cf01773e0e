"""Noun phrases: determiner, count, colour, size, speed and head noun; and where a new clause starts."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from ...colors import is_color_word, match_color
from ..grounding import ALL_WORDS, CAMERA_WORDS
from ..lexicon import (
    AUX,
    CLAUSE_JOINERS,
    COLLECTIVE_NOUNS,
    DETS,
    GENERIC_NOUNS,
    INTENSIFIERS,
    POSSESSIVE_ATTRIBUTES,
    PRONOUNS,
    SEGMENT_PUNCT,
    SIZE_WORDS,
    SPEED_PHRASES,
    SPEED_WORDS_1,
    STATIONARY,
    VERBS,
    VIEWERS,
)
from .. import hypernyms, wordnet
from ..vocabulary import CATEGORIES, noun_to_category, word_to_setting
from .tokens import NUMBER_PHRASES, SIZE_PHRASES, is_adverb, known_word, match_phrase, number_at, stop_word

__all__ = ["NounPhrase", "clause_boundary", "parse_np"]


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
    """A noun phrase starting at i, or None when none starts there.

    Reads, in order: a pronoun (the whole phrase), a determiner, a count ("two", "a herd of"),
    then modifiers (colour, size, speed) and nouns up to a word that ends the phrase; the last
    noun is the head."""
    if i >= len(toks):
        return None
    pronoun = _pronoun(toks, i)
    if pronoun is not None:
        return pronoun
    np_ = NounPhrase(start=i, end=i, words=[])
    j = _count(toks, _determiner(toks, i, np_), np_)
    collected = _phrase_words(toks, j, np_, edit)
    if not collected:
        return None  # also "the two" / "both": a number used as a noun phrase
    collected = _drop_trailing_verb(toks, collected)
    head_i = collected[-1]
    np_.head = toks[head_i]
    np_.start, np_.end = i, head_i + 1
    np_.words = list(toks[i:head_i + 1])
    whole = len(collected) >= 2 and collected[-2] == head_i - 1 and compound_noun(toks[head_i - 1], np_.head)
    for k in collected[:-1]:
        s = word_to_setting(toks[k])
        if s is not None and noun_to_category(toks[k]) is None and not (whole and k == head_i - 1):
            np_.settings.append(s)   # "a dog in snowy fields", not the "ice" of "an ice cream"
    _classify_head(np_)
    if whole and np_.kind == "category" and hypernyms.names_other_thing(f"{toks[head_i - 1]} {np_.head}", np_.category):
        np_.kind, np_.category = "unknown", None   # "a hot dog" is food: grounded whole, not as the dog
    return np_


def _pronoun(toks: Sequence[str], i: int) -> NounPhrase | None:
    """ "it", "them", or a possessive standing alone ("its motion", "their speed")."""
    w = toks[i]
    if w in PRONOUNS and w not in ("both", "its", "their", "his", "her"):
        plural = w in ("them", "they", "themselves")
    elif w in ("its", "their") and (i + 1 >= len(toks) or stop_word(toks[i + 1]) or toks[i + 1] in POSSESSIVE_ATTRIBUTES):
        plural = w == "their"
    else:
        return None
    return NounPhrase(start=i, end=i + 1, words=[w], kind="pronoun", head=w, plural=plural)


def _determiner(toks: Sequence[str], i: int, np_: NounPhrase) -> int:
    """Reads "a", "the", "all of the"... into ``np_.det``; returns the index after it."""
    n = len(toks)
    w = toks[i]
    j = i
    if w in ("a", "an") and i + 1 < n and match_phrase(toks, i, NUMBER_PHRASES) is None:
        np_.det, j = w, i + 1
    elif w in ("all", "both", "each", "every") and i + 1 < n and toks[i + 1] == "of":
        np_.det, j = w, i + 2
        if j < n and toks[j] in ("the", "these", "those"):
            j += 1
    elif w in DETS and (w not in ("all", "every", "each", "both") or i + 1 < n):
        np_.det, j = w, i + 1
    if np_.det == "both":
        np_.count = 2
    return j


def _count(toks: Sequence[str], j: int, np_: NounPhrase) -> int:
    """Reads "two", "twenty five", "a herd of (the)"; returns the index after it."""
    n = len(toks)
    num = number_at(toks, j)
    if num is not None and not (j + num[1] < n and toks[j + num[1]] in ("times", "percent", "%")):
        np_.count = num[0]
        j += num[1]
    if j + 1 < n and toks[j] in COLLECTIVE_NOUNS and toks[j + 1] == "of":
        np_.collective = True
        j += 2
        if j < n and toks[j] == "the":
            j += 1
    return j


def _phrase_words(toks: Sequence[str], j: int, np_: NounPhrase, edit: bool) -> list[int]:
    """Indices of the modifier and noun words from j on (colour, size and speed go into `np_`)."""
    n = len(toks)
    collected: list[int] = []
    known_head = False
    while j < n:
        if toks[j] == ",":
            if not _comma_continues(toks, j, collected, known_head):
                break
            j += 1
            continue
        if _next_phrase_starts(toks, j, collected, known_head):
            break
        if collected and collected[-1] == j - 1 and compound_noun(toks[j - 1], toks[j]):
            collected.append(j)      # the second word of a compound noun: "ice cream" (not the colour cream)
            known_head = known_head or _is_known_noun(toks[j], edit)
            j += 1
            continue
        col = match_color(toks, j)
        if col is not None:
            after = toks[j + col[2]] if j + col[2] < n else None
            if _colour_is_modifier(after, np_, edit):
                np_.color = np_.color or (col[0], col[1])  # "tomato red": the first colour names it
                collected.extend(range(j, j + col[2]))
                j += col[2]
                continue
            if collected and (after is None or stop_word(after)):
                break  # "make the vehicle blue": a trailing colour is the complement, not the noun
        if _ends_phrase(toks, j, np_, collected):
            break
        k = _size_or_speed(toks, j, np_)
        if k:
            collected.extend(range(j, j + k))
            j += k
            continue
        if toks[j] not in INTENSIFIERS:
            collected.append(j)
            known_head = known_head or _is_known_noun(toks[j], edit)
        j += 1
    return collected


def _comma_continues(toks: Sequence[str], j: int, collected: list[int], known_head: bool) -> bool:
    """A comma between modifiers ("a big, red ball") continues the phrase."""
    nxt = toks[j + 1] if j + 1 < len(toks) else ""
    return bool(collected and not known_head and nxt and not stop_word(nxt) and nxt not in DETS
                and number_at(toks, j + 1) is None and "," not in nxt)


def _next_phrase_starts(toks: Sequence[str], j: int, collected: list[int], known_head: bool) -> bool:
    w = toks[j]
    if collected and w in DETS and w not in ("all", "every", "each"):
        return True  # an article starts the next phrase ("a retriever fetches a ball")
    # after a known noun only another known noun continues the phrase ("table lamp"), or the rest
    # of a compound WordNet knows that names another thing ("an aircraft carrier" is no aircraft)
    return known_head and noun_to_category(w) is None and not _other_thing_compound(toks, j, collected)


def _other_thing_compound(toks: Sequence[str], j: int, collected: list[int]) -> bool:
    """Whether the vocabulary noun before j and the word at j (no verb: "the bus stops") are a
    compound WordNet knows that is not a kind of the noun's category ("aircraft carrier", "jet bridge")."""
    w, prev = toks[j], toks[j - 1]
    if not collected or collected[-1] != j - 1 or w in VERBS or w in AUX:
        return False
    cat = noun_to_category(prev)
    return cat is not None and compound_noun(prev, w) and hypernyms.names_other_thing(f"{prev} {w}", cat[0])


def _colour_is_modifier(after: str | None, np_: NounPhrase, edit: bool) -> bool:
    """A colour modifies the noun only when more of the phrase follows it."""
    return bool(after is not None and after != "'s" and (
        not stop_word(after) or (after == "," and not edit) or noun_to_category(after)
        or (word_to_setting(after) and np_.det is not None)))


def _ends_phrase(toks: Sequence[str], j: int, np_: NounPhrase, collected: list[int]) -> bool:
    """Whether the word at j ends the phrase (a verb, preposition, conjunction...)."""
    w = toks[j]
    nxt = toks[j + 1] if j + 1 < len(toks) else None
    if w in INTENSIFIERS and nxt is not None and (nxt in SPEED_WORDS_1 or f"{w} {nxt}" in SIZE_WORDS):
        return False  # "very small" / "very fast": the phrase tables see both words
    if not stop_word(w) or (w in SPEED_WORDS_1 and nxt is not None and not stop_word(nxt)):
        return False
    after = toks[j + 2] if j + 2 < len(toks) else None
    if _noun_not_verb(w, nxt, np_, [toks[k] for k in collected], after):
        return False
    if np_.det is not None and w in VERBS and nxt is not None and not stop_word(nxt) and not known_word(nxt) \
            and (after in VERBS or after in AUX):
        return False  # a verb-like word of an unknown compound noun before its verb: "a red go kart moves"
    # nouns that are also verbs: "the park", "a yellow taxi speeds"
    if word_to_setting(w) or noun_to_category(w):
        if not collected and np_.det is not None:
            return False
        if collected and (nxt is None or nxt in VERBS or nxt in AUX):
            return False
    return True


def _noun_not_verb(w: str, nxt: str | None, np_: NounPhrase, collected: list[str], after: str | None = None) -> bool:
    """A stop word that is a noun here: a word of a compound noun WordNet knows ("a frying pan", not
    the camera's pan; "a parking meter"), a verb before a visible noun that ends the phrase ("a stop
    sign"), or a verb that is a visible thing alone after an article ("a swing", "a swing sways")."""
    if collected and compound_noun(collected[-1], w):
        return True
    if np_.det is not None and nxt is not None and compound_noun(w, nxt):
        return True          # the first word of a compound noun: "a parking meter", "a swing seat"
    if np_.det is not None and w in VERBS and all(is_color_word(c) or c in SIZE_WORDS for c in collected) \
            and nxt is not None and not stop_word(nxt) and wordnet.is_visible_noun(nxt) and (after is None or stop_word(after)):
        return True          # a verb modifying a noun that ends the phrase: "a stop sign", "a red stop sign on the road"
    return bool(np_.det is not None and not collected and w in VERBS and (nxt is None or nxt in VERBS or nxt in AUX)
                and hypernyms.ranked_senses(w))


def compound_noun(first: str, second: str) -> bool:
    """Whether the two words are a compound noun WordNet knows ("frying pan", "go kart" as "go-kart")."""
    return first.isalpha() and second.isalpha() and bool(wordnet.senses(f"{first} {second}", 1))


def _size_or_speed(toks: Sequence[str], j: int, np_: NounPhrase) -> int:
    """Reads a size ("very small") or speed ("fast") modifier at j into `np_`; how many words."""
    n = len(toks)
    sz = match_phrase(toks, j, SIZE_PHRASES)
    if sz is not None and j + sz[1] < n and (not stop_word(toks[j + sz[1]]) or toks[j + sz[1]] == ","):
        np_.size, np_.scale = sz[0], SIZE_WORDS[sz[0]]
        return sz[1]
    sp = match_phrase(toks, j, SPEED_PHRASES)
    if sp is not None and j + sp[1] < n and not stop_word(toks[j + sp[1]]):
        np_.speed = (sp[0], " ".join(toks[j:j + sp[1]]))
        return sp[1]
    return 0


def _is_known_noun(w: str, edit: bool) -> bool:
    return (noun_to_category(w) is not None or (edit and bool(word_to_setting(w))) or w in CAMERA_WORDS
            or (w in ALL_WORDS and w != "all"))


def _drop_trailing_verb(toks: Sequence[str], collected: list[int]) -> list[int]:
    """An unknown word ending in -s right after a noun is probably an unknown verb ("a sedan skids")."""
    unknown = [k for k in collected if not known_word(toks[k])]
    last = toks[collected[-1]]
    if len(collected) >= 2 and len(unknown) >= 2 and collected[-1] == unknown[-1] and last.endswith("s") \
            and not last.endswith("ss"):
        return collected[:-1]
    return collected


def _classify_head(np_: NounPhrase) -> None:
    """Sets ``kind`` (camera, viewer, all, category, setting, generic, unknown), ``category`` and
    ``plural`` from the head noun."""
    head = np_.head
    hit = noun_to_category(head)
    setting = word_to_setting(head)
    if head in CAMERA_WORDS:
        np_.kind = "camera"
    elif head in VIEWERS or head in ("viewer", "camera"):
        np_.kind = "viewer"
    elif head in ALL_WORDS or head in ("scene", "all"):
        np_.kind = "all"
    elif hit is not None and (setting is None or head == "table" or head in CATEGORIES) \
            and not hypernyms.synonym_sibling(head):    # "stool" is no chair: grounded as an open noun
        np_.kind, np_.category, np_.plural = "category", hit[0], hit[1]
    elif setting is not None:
        np_.kind, np_.category = "setting", setting
    elif head in GENERIC_NOUNS:
        np_.kind = "all" if GENERIC_NOUNS[head] or np_.det in ("all", "every", "each") else "generic"
    else:
        np_.kind = "unknown"
        np_.plural = head.endswith("s") and not head.endswith("ss") and len(head) > 3
    if np_.kind == "category" and np_.det in ("all", "every", "each") and not np_.plural:
        np_.plural = np_.det != "each"


def clause_boundary(toks: Sequence[str], k: int) -> bool:
    """Whether a new clause (with its own subject) starts at token k."""
    w = toks[k]
    if w in SEGMENT_PUNCT:
        return True
    if w not in CLAUSE_JOINERS:
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
