"""Motion phrases: verbs, directions, sides, paths, speeds and landmarks of a clause (`Predicate`),
and how they combine into one motion."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from ...errors import CommandError
from ..lexicon import (
    DIRECTIONS,
    SIDE_FRAME_WORDS,
    SIDE_TAIL,
    SIDE_WORDS,
    vec_norm,
)
from .nouns import NounPhrase
from .tokens import detok

__all__ = ["Predicate", "combine_directions", "direction_of", "merge_motion", "merge_pred", "path_of", "side_at"]


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
    mutual: bool = False  # "towards each other": two subjects that meet

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
        if toks[j] == "of" and not (j + 1 < n and toks[j + 1] in SIDE_FRAME_WORDS):
            break
        j += 1
    return side, j - i


def direction_of(name: str) -> tuple[float, float, float]:
    return DIRECTIONS[name]


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
    dst.mutual = dst.mutual or src.mutual
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
