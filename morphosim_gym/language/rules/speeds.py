"""Relative speed phrases: "twice as fast", "half as fast", "at half speed", "3 times faster",
"50 percent slower", "faster (than before)", "slow down"."""

from __future__ import annotations

from collections.abc import Sequence

from ...errors import CommandError
from ..lexicon import (
    AS_SPEED_FACTORS,
    BIT_WORDS,
    FAST_COMPARATIVES,
    FRACTION_FACTORS,
    MUCH_WORDS,
    NUMBER_WORDS,
    SPEED_TIMES_FILLERS,
)
from .tokens import is_number, number_at

__all__ = ["relative_speed"]

Hit = tuple[float, int]  # (factor, index after the phrase)


def relative_speed(toks: Sequence[str], i: int, allow_bare: bool = False) -> Hit | None:
    """``(factor, index after the phrase)`` of a relative speed phrase at i, or None.
    `allow_bare`: also read "speed up" / "slow down".

    Raises:
        CommandError: a negative or zero factor ("minus two times as fast", "100 percent slower").
    """
    w = toks[i]
    end = len(toks)
    if w in ("minus", "negative") and i + 1 < end and (is_number(toks[i + 1]) or toks[i + 1] in NUMBER_WORDS):
        raise CommandError(f"Could not use a negative speed factor in {' '.join(toks[i:end])!r}: the factor "
                           f"must be > 0 (say 'reverse' to reverse a motion)")
    hit = _fixed_factor(toks, i) or _counted_or_bare(toks, i, allow_bare)
    if hit is None:
        return None
    factor, j = hit
    if factor <= 0:
        raise CommandError(f"Could not use the speed change {' '.join(toks[i:j])!r}: the speed factor must be "
                           f"> 0 (say 'stop' to stop a motion)")
    return round(factor, 6), j


def _fixed_factor(toks: Sequence[str], i: int) -> Hit | None:
    """ "twice as fast", "half as fast", "twice as slowly", "at half speed", "double speed"."""
    w = toks[i]
    end = len(toks)
    if i + 2 < end and toks[i + 1] == "as" and (w, toks[i + 2]) in AS_SPEED_FACTORS:
        return AS_SPEED_FACTORS[(w, toks[i + 2])], i + 3
    if w in ("at", "to") and i + 2 < end and toks[i + 1] in FRACTION_FACTORS and toks[i + 2] in ("speed", "the"):
        j = i + 3
        if toks[j - 1] == "the" and j < end and toks[j] == "speed":
            j += 1
        return FRACTION_FACTORS[toks[i + 1]], j
    if w in ("half", "double", "triple") and i + 1 < end and toks[i + 1] in ("speed", "pace"):
        return FRACTION_FACTORS[w], i + 2
    return None


def _counted_or_bare(toks: Sequence[str], i: int, allow_bare: bool) -> Hit | None:
    w = toks[i]
    num = number_at(toks, i) if (is_number(w) or w in NUMBER_WORDS) else None
    if num is not None and i + num[1] < len(toks) and toks[i + num[1]] in ("times", "percent"):
        return _counted(toks, i, num)
    if allow_bare or w in FAST_COMPARATIVES or w == "slower":
        return _bare(toks, i)
    return None


def _counted(toks: Sequence[str], i: int, num: tuple[int, int]) -> Hit | None:
    """ "3 times faster", "2 times as fast (as)", "3 times the speed", "50 percent slower"."""
    end = len(toks)
    value, k = num
    unit = toks[i + k]
    j = i + k + 1
    if j < end and toks[j] == "as" and j + 1 < end and toks[j + 1] in ("fast", "quickly", "quick", "slow", "slowly"):
        slow = toks[j + 1] in ("slow", "slowly")
        j += 2
        if j < end and toks[j] == "as":
            j += 1
    elif j < end and toks[j] in ("faster", "quicker", "slower", "more"):
        slow = toks[j] == "slower"
        j += 1
        if toks[j - 1] == "more" and j < end and toks[j] in ("slowly", "quickly"):
            slow = toks[j] == "slowly"
            j += 1
    elif unit == "times" and j < end and toks[j] in ("the", "normal", "its", "their", "speed"):
        slow = False
        while j < end and toks[j] in SPEED_TIMES_FILLERS:
            j += 1
    else:
        return None
    if unit == "percent":
        return 1.0 + value / 100.0 * (-1 if slow else 1), j
    if value == 0:
        return 0.0, j
    return (1.0 / value if slow else float(value)), j


def _bare(toks: Sequence[str], i: int) -> Hit | None:
    """ "faster", "much slower", "a bit faster (than before)", "speed up", "slow down"."""
    w = toks[i]
    end = len(toks)
    mod = 1.0
    if i >= 1 and toks[i - 1] in MUCH_WORDS:
        mod = 2.0
    elif i >= 1 and toks[i - 1] in BIT_WORDS:
        mod = 0.5
    if w in FAST_COMPARATIVES or (w == "speed" and i + 1 < end and toks[i + 1] == "up"):
        factor = {1.0: 2.0, 2.0: 3.0, 0.5: 1.25}[mod]
    elif w == "slower" or (w == "slow" and i + 1 < end and toks[i + 1] == "down"):
        factor = {1.0: 0.5, 2.0: round(1 / 3, 6), 0.5: 0.8}[mod]
    else:
        return None
    j = i + (2 if w in ("speed", "slow") else 1)
    if j < end and toks[j] == "than" and j + 1 < end:  # "faster than before/now"
        j += 2
    return factor, j
