"""Count words with no usable bound ("a billion balls", "countless cubes", "1e9 mugs"): a clear
`CommandError` instead of the plural default of 3 objects the parser would otherwise fall back to."""

from __future__ import annotations

import re
from collections.abc import Sequence

from ..errors import CommandError
from .plan import MAX_COUNT

__all__ = ["UNBOUNDED_COUNT_WORDS", "refuse_unbounded_count"]

UNBOUNDED_COUNT_WORDS = frozenset({
    "billion", "billions", "trillion", "trillions", "quadrillion", "quintillion", "sextillion", "septillion",
    "octillion", "nonillion", "decillion", "zillion", "zillions", "gazillion", "gazillions", "bazillion",
    "jillion", "kajillion", "squillion", "googol", "googolplex", "umpteen", "countless", "innumerable",
    "infinity", "millions", "thousands", "hundreds",
})
_DIGITS = re.compile(r"\d+")


def refuse_unbounded_count(toks: Sequence[str], i: int) -> None:
    """`CommandError` if the count at token `i` is far beyond what a scene can hold: a word like
    "billion", or scientific notation ("1e9", which the tokenizer splits into "1", "e", "9")."""
    word = toks[i]
    scientific = (_DIGITS.fullmatch(word) is not None and i + 2 < len(toks) and toks[i + 1] == "e"
                  and _DIGITS.fullmatch(toks[i + 2]) is not None)
    if word in UNBOUNDED_COUNT_WORDS or scientific:
        shown = " ".join(toks[i:i + 3]).replace(" e ", "e") if scientific else word
        raise CommandError(f"Could not generate {shown!r} objects: the count must be a number between 1 and "
                           f"{MAX_COUNT} (e.g. 'three balls')")
