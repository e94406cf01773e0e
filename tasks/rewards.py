"""Shaped reward terms in [0, 1], in the manner of dm_control's `tolerance`.

`tolerance(x, bounds=(lo, hi), margin=m)` is 1 inside [lo, hi] and falls off outside with
a chosen shape, reaching `value_at_margin` at distance `m` from the nearest bound. With
`margin=0` it is an indicator of the interval.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["tolerance", "SIGMOIDS"]

SIGMOIDS = ("gaussian", "linear", "quadratic", "long_tail", "reciprocal")


def _shape(d: np.ndarray, sigmoid: str, value_at_margin: float) -> np.ndarray:
    """A decreasing function of the scaled distance d >= 0 with value 1 at 0 and `value_at_margin` at 1."""
    v = value_at_margin
    if sigmoid == "gaussian":
        k = math.sqrt(-2.0 * math.log(v))
        return np.exp(-0.5 * (d * k) ** 2)
    if sigmoid == "long_tail":
        k = math.sqrt(1.0 / v - 1.0)
        return 1.0 / ((d * k) ** 2 + 1.0)
    if sigmoid == "reciprocal":
        k = 1.0 / v - 1.0
        return 1.0 / (np.abs(d) * k + 1.0)
    if sigmoid == "linear":
        k = 1.0 - v
        s = d * k
        return np.where(np.abs(s) < 1.0, 1.0 - s, 0.0)
    if sigmoid == "quadratic":
        k = math.sqrt(1.0 - v)
        s = d * k
        return np.where(np.abs(s) < 1.0, 1.0 - s * s, 0.0)
    raise ValueError(f"Expected sigmoid in {SIGMOIDS}, found {sigmoid!r}")


def _scalar(x: float, lo: float, hi: float, margin: float, sigmoid: str, value_at_margin: float) -> float:
    """`tolerance` of one number (the per-step reward path): the array path's arithmetic on floats,
    so the value is the same to the bit (exp through numpy, as there)."""
    if lo <= x <= hi:
        return 1.0
    if margin == 0:
        return 0.0
    d = (lo - x if x < lo else x - hi) / margin           # NaN stays NaN, as in the array path
    return _shape_scalar(max(d, 0.0), sigmoid, value_at_margin)


def _shape_scalar(d: float, sigmoid: str, v: float) -> float:
    """`_shape` of one number."""
    if sigmoid == "gaussian":
        s = d * math.sqrt(-2.0 * math.log(v))
        return float(np.exp(-0.5 * (s * s)))
    if sigmoid == "long_tail":
        s = d * math.sqrt(1.0 / v - 1.0)
        return 1.0 / (s * s + 1.0)
    return float(_shape(np.float64(d), sigmoid, v))


def tolerance(x, bounds: tuple[float, float] = (0.0, 0.0), margin: float = 0.0, sigmoid: str = "gaussian",
              value_at_margin: float = 0.1):
    """1 where `bounds[0] <= x <= bounds[1]`, decaying to `value_at_margin` at `margin` outside.

    Args:
        x: a number or an array.
        bounds: (lower, upper), lower <= upper (either may be +-inf).
        margin: distance from the bounds at which the value is `value_at_margin`; 0 gives an indicator.
        sigmoid: "gaussian", "linear", "quadratic", "long_tail" or "reciprocal".
        value_at_margin: in (0, 1) (for "linear"/"quadratic" also 0 is allowed).

    Returns:
        float (for a number) or an array of the shape of `x`, in [0, 1].

    Examples:
        >>> tolerance(0.5, bounds=(0, 1))
        1.0
        >>> round(tolerance(2.0, bounds=(0, 1), margin=1.0), 3)
        0.1
    """
    lo, hi = float(bounds[0]), float(bounds[1])
    if lo > hi:
        raise ValueError(f"Expected bounds (lower, upper) with lower <= upper, found {bounds!r}")
    if margin < 0:
        raise ValueError(f"Expected margin >= 0, found {margin!r}")
    if not 0.0 <= value_at_margin < 1.0 or (value_at_margin == 0.0 and sigmoid not in ("linear", "quadratic")):
        raise ValueError(f"Expected value_at_margin in (0, 1), found {value_at_margin!r}")
    if type(x) is float or type(x) is int or type(x) is np.float64:
        return _scalar(float(x), lo, hi, margin, sigmoid, value_at_margin)
    arr = np.asarray(x, dtype=np.float64)
    inside = (arr >= lo) & (arr <= hi)
    if margin == 0:
        out = np.where(inside, 1.0, 0.0)
    else:
        d = np.where(arr < lo, lo - arr, arr - hi) / margin
        out = np.where(inside, 1.0, _shape(np.maximum(d, 0.0), sigmoid, value_at_margin))
    return float(out) if np.ndim(out) == 0 else out
