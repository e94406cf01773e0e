"""Tokens: the normalised word list of a command, and small word tests and matchers on it."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

from ...colors import is_color_word, match_color
from ...errors import CommandError
from .. import wordnet
from ..count_words import refuse_unbounded_count
from ..lexicon import (
    AUX,
    CLOCKWISE_WORDS,
    COLLECTIVE_NOUNS,
    COMPOUNDS,
    CONJ,
    CONTRACTIONS,
    DETS,
    DIRECTION_WORDS,
    EDIT_STOP_VERBS,
    INTENSIFIERS,
    ITS_NEXT,
    NUMBER_WORDS,
    PREPS,
    RELATIVE,
    SEGMENT_PUNCT,
    SIZE_WORDS,
    STATIONARY,
    VERBS,
    lexicon_words,
)
from ..vocabulary import noun_to_category

__all__ = [
    "NUMBER_PHRASES",
    "SIZE_PHRASES",
    "detok",
    "is_adverb",
    "is_number",
    "known_word",
    "match_phrase",
    "number_at",
    "stop_word",
    "tokenize",
]


_COMPOUND_RE = re.compile(r"\b(" + "|".join(re.escape(k) for k in sorted(COMPOUNDS, key=len, reverse=True)) + r")\b")


_TOKEN_RE = re.compile(r"css:[a-z]+|-?\d+(?:\.\d+)?|[a-z]+(?:'[a-z]+)?|[.,;!?:]")
# "css: dark olive green" -> "css:darkolivegreen": one token for an exact CSS colour (see `colors`)
_CSS_RE = re.compile(r"\bcss:\s*((?:[a-z]+\s*){1,4})")


def _css_token(m: re.Match) -> str:
    words = m.group(1).split()
    for k in range(len(words), 0, -1):
        if is_color_word("css:" + "".join(words[:k])):
            return "css:" + "".join(words[:k]) + " " + " ".join(words[k:]) + " "
    return m.group(0)


_POWER_RE = re.compile(r"(\d{1,6})\s*(?:\^|\*\*)\s*(\d{1,6})")


def _power(m: re.Match) -> str:
    """ "10^9" / "2**3" as the number it is when small ("8"), else as scientific notation ("1 e 9",
    which the count check refuses); the token pattern has no "^", which would leave "10 9"."""
    base, exp = int(m.group(1)), int(m.group(2))
    if base <= 1 or exp * math.log10(base) < 7:
        return str(base ** exp)
    return f"1 e {int(exp * math.log10(base))}"


def tokenize(text: str) -> list[str]:
    """Lower-cased word, number and punctuation tokens with the parser's normalisations."""
    t = _CSS_RE.sub(_css_token, _POWER_RE.sub(_power, text.lower()))
    t = (t.replace("\u2019", "'").replace("\u2018", "'").replace("\u201c", '"').replace("\u201d", '"')
         .replace("\u2014", " , ").replace("\u2013", " , ").replace("`", "'"))
    t = re.sub(r"(\d)\s*x\b", r"\1 times", t)
    t = re.sub(r"(\d)\s*%", r"\1 percent", t)
    t = _COMPOUND_RE.sub(lambda m: COMPOUNDS[m.group(1)], t)
    t = re.sub(r"(?<=[a-z])-(?=[a-z])", " ", t)
    out: list[str] = []
    raw = _TOKEN_RE.findall(t)
    for i, w in enumerate(raw):
        if w in CONTRACTIONS:
            out.extend(CONTRACTIONS[w])
        elif w == "it's":
            nxt = raw[i + 1] if i + 1 < len(raw) else ""
            out.extend(["its"] if nxt in ITS_NEXT else ["it", "is"])
        elif w.endswith("'s") and len(w) > 2:
            out.extend([w[:-2], "'s"])
        elif w.endswith("s'") and len(w) > 2:
            out.extend([w[:-1], "'s"])
        elif "'" in w:
            out.append(w.replace("'", ""))
        else:
            out.append(w)
    return [COMPOUNDS.get(w, w) for w in out]


def is_adverb(w: str) -> bool:
    """A 6+ letter "-ly" word that names no thing: "slowly", "steadily" are adverbs; "butterfly",
    "dragonfly" (WordNet nouns one can see) and vocabulary nouns are not."""
    return (len(w) >= 6 and w.endswith("ly") and noun_to_category(w) is None and w not in COLLECTIVE_NOUNS
            and not wordnet.is_visible_noun(w))


def is_number(w: str) -> bool:
    return bool(re.fullmatch(r"-?\d+(?:\.\d+)?", w))


def stop_word(w: str) -> bool:
    """Words that end a noun phrase."""
    return (w in VERBS or w in AUX or w in PREPS or w in CONJ or w in RELATIVE or w in SEGMENT_PUNCT or w == ","
            or w in DIRECTION_WORDS or w in CLOCKWISE_WORDS or w in ("'s", "not", "than", "of", "until", "when",
                                                                      "if", "because", "before", "there", "here",
                                                                      "now", "again", "instead", "too")
            or w in STATIONARY or is_adverb(w) or w in EDIT_STOP_VERBS)


def match_phrase(toks: Sequence[str], i: int, table: dict[tuple[str, ...], Any]) -> tuple[Any, int] | None:
    for k in (5, 4, 3, 2, 1):
        key = tuple(toks[i:i + k])
        if len(key) == k and key in table:
            return table[key], k
    return None


NUMBER_PHRASES = {tuple(k.split()): v for k, v in NUMBER_WORDS.items()}


# number words that combine into compound numbers (no "a few" / "several")
_COMPOUND_NUMBER = {k: v for k, v in NUMBER_WORDS.items() if " " not in k and k not in (
    "single", "both", "several", "few", "some", "many", "multiple", "dozen")}


SIZE_PHRASES = {tuple(k.split()): k for k in SIZE_WORDS}


def number_at(toks: Sequence[str], i: int) -> tuple[int, int] | None:
    if i >= len(toks):
        return None
    w = toks[i]
    refuse_unbounded_count(toks, i)
    if is_number(w):
        v = float(w)
        if v != int(v):
            raise CommandError(f"Could not understand the count {w!r}: expected a whole number of objects")
        value, used = int(v), 1
    else:
        hit = match_phrase(toks, i, NUMBER_PHRASES)
        if hit is None:
            return None
        value, used = hit
        if not (toks[i] in _COMPOUND_NUMBER or toks[i] == "a"):
            return hit                     # "a few", "several", "both": no arithmetic
    # compound numbers: "twenty five" = 25, "ten thousand" = 10000, "two hundred and six" = 206
    total, current = 0, value
    j = i + used
    while j < len(toks):
        w = toks[j]
        if w == "and" and j + 1 < len(toks) and toks[j + 1] in _COMPOUND_NUMBER and current >= 100:
            j += 1
            continue
        refuse_unbounded_count(toks, j)
        v = _COMPOUND_NUMBER.get(w)
        if v is None:
            break
        if v in (100, 1000, 1000000):
            current = max(current, 1) * v
            if v >= 1000:
                total, current = total + current, 0
        elif v < 10 and ((current % 100 >= 20 and current % 10 == 0) or (current >= 100 and current % 100 == 0)):
            current += v               # "twenty five", "two hundred five"
        elif 10 <= v < 100 and current >= 100 and current % 100 == 0:
            current += v               # "two hundred twenty"
        else:
            break
        j += 1
    return total + current, j - i


def known_word(w: str) -> bool:
    return (w in lexicon_words() or w in DETS or w in PREPS or w in CONJ or w in AUX or w in INTENSIFIERS
            or match_color([w]) is not None or is_number(w))


def detok(toks: Sequence[str]) -> str:
    s = " ".join(toks)
    return s.replace(" 's", "'s").replace(" ,", ",")
