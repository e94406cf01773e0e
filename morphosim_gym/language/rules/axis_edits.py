"""Edit sentences of the perturbation axes: size, swap, insertion, lighting, sky, texture, setting,
camera view, sensor and time offset.

    make the ball twice as big | shrink the cube | enlarge the ball by 1.5        -> scale
    replace the ball with a cube | swap the ball for a red cube | turn the ball into a cube -> swap
    add a blue cube next to the ball | add a box behind the ball                   -> insert
    put a box between the camera and the ball                                      -> insert (occluding)
    dim the lights | make the light warmer | light the scene from the left         -> light
    make the sky a sunset | change the sky to night                                -> sky
    make the ball checkered | make the ground striped | make the cube metallic     -> texture
    move the scene to snow | set the scene on the beach                            -> setting
    widen the field of view | raise the camera by 1 metre | lower the camera       -> view
    add sensor noise | blur the images | compress the video                        -> sensor
    delay the ball's motion by 1 second | make the ball start 2 seconds earlier     -> delay

Each reader is registered in `AXIS_READERS` (a `WordTable`) under the words a sentence starts
with; `EditReader` tries them before its own verb readers. A reader returns op drafts (dicts of
`EditOp` fields, targets unresolved) or None when the sentence is not its construction.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ...colors import match_color
from ...errors import CommandError
from ..lexicon import AXIS_WORDS
from ..plan import ColorSpec
from ..vocabulary import SETTING_WORDS, noun_to_category
from .dispatch import WordTable
from .tokens import is_number

__all__ = ["AXIS_READERS", "AXIS_VERBS"]

AXIS_READERS = WordTable()

_NUMBER_WORDS = {"a": 1.0, "an": 1.0, "one": 1.0, "two": 2.0, "three": 3.0, "four": 4.0, "five": 5.0, "half": 0.5,
                 "twice": 2.0, "thrice": 3.0}
_SIZE_WORDS = {"bigger": 1.5, "larger": 1.5, "huge": 2.5, "giant": 2.5, "smaller": 0.67, "tiny": 0.4, "big": 1.5,
               "large": 1.5, "small": 0.67}
_SKY_WORDS = {"sunset": "sunset", "dusk": "sunset", "evening": "sunset", "cloudy": "overcast", "overcast": "overcast",
              "night": "night", "starry": "night", "nighttime": "night", "clear": "clear", "sunny": "clear",
              "dawn": "dawn", "sunrise": "dawn", "morning": "dawn"}
_TEXTURE_WORDS = {"checkered": "checkered", "checked": "checkered", "chequered": "checkered", "striped": "striped",
                  "stripy": "striped", "dotted": "dotted", "spotted": "dotted", "polka": "dotted",
                  "metallic": "metallic", "metal": "metallic", "chrome": "metallic", "matte": "matte", "matt": "matte",
                  "shiny": "glossy", "glossy": "glossy", "noisy": "noisy", "speckled": "noisy", "grainy": "noisy"}
_LIGHT_BRIGHTNESS = {"brighter": 1.4, "dimmer": 0.6, "darker": 0.6, "lighter": 1.4}
_LIGHT_TEMPERATURE = {"warmer": 0.6, "warm": 0.6, "cooler": -0.6, "cool": -0.6, "colder": -0.6, "cold": -0.6,
                      "bluer": -0.6, "yellower": 0.6}
_LIGHT_NOUNS = ("light", "lights", "lighting", "illumination", "sun", "sunlight")
_FROM_DIRECTIONS = {"left": (-1.0, 0.0, 0.0), "right": (1.0, 0.0, 0.0), "front": (0.0, -1.0, 0.0),
                    "behind": (0.0, 1.0, 0.0), "back": (0.0, 1.0, 0.0), "camera": (0.0, -1.0, 0.0)}
_SENSOR_WORDS = {"noise": "noise", "noisy": "noise", "grain": "noise", "grainy": "noise", "blur": "blur",
                 "blurry": "blur", "blurred": "blur", "compression": "jpeg", "compressed": "jpeg", "jpeg": "jpeg",
                 "artifacts": "jpeg", "artefacts": "jpeg"}
_SENSOR_NOUNS = ("camera", "cameras", "image", "images", "video", "view", "picture", "pictures", "sensor", "frames",
                 "observations", "lens")
_AMOUNTS = {"little": 0.25, "bit": 0.25, "slight": 0.25, "slightly": 0.25, "some": 0.5, "lot": 0.9, "heavy": 0.9,
            "heavily": 0.9, "strong": 0.9, "strongly": 0.9, "much": 0.9, "alot": 0.9}
_SCENE_WORDS = ("scene", "everything", "world", "whole", "setting", "background")
_UNITS = {"m": 1.0, "metre": 1.0, "metres": 1.0, "meter": 1.0, "meters": 1.0, "cm": 0.01, "centimetres": 0.01,
          "centimeters": 0.01, "centimetre": 0.01, "centimeter": 0.01}
_SECONDS = ("s", "second", "seconds", "sec", "secs")


def _number(w: str) -> float | None:
    if is_number(w):
        return float(w)
    return _NUMBER_WORDS.get(w)


def _color(toks: Sequence[str], i: int) -> tuple[ColorSpec | None, int]:
    """A colour at i (and the index after it)."""
    col = match_color(list(toks), i) if i < len(toks) else None
    if col is None:
        return None, i
    return ColorSpec(col[0], col[1]), i + col[2]


def _new_object(toks: Sequence[str], i: int) -> tuple[str, ColorSpec | None, int] | None:
    """ "a [colour] cube" at i: (category, colour, index after), or None when no known noun follows."""
    if i < len(toks) and toks[i] in ("a", "an", "another", "one", "some"):     # a new object: never "the"
        i += 1
    color, i = _color(toks, i)
    if i >= len(toks):
        return None
    hit = noun_to_category(toks[i])
    if hit is None:
        return None
    return hit[0], color, i + 1


def _targets_or_none(reader: Any, toks: Sequence[str]) -> tuple[list, int] | None:
    """The targets at the start of `toks`, or None when there are none (not this construction)."""
    try:
        return reader._targets(list(toks))
    except CommandError:
        return None


def _scene_target(toks: Sequence[str]) -> bool:
    return any(w in _SCENE_WORDS for w in toks[:3])


# ----------------------------------------------------------------- size
def _size_factor(tail: Sequence[str]) -> float | None:
    """ "twice as big", "3 times bigger", "half as big", "bigger", "half the size"."""
    t = [w for w in tail if w not in ("be", "look", "become", "much", "a", "lot", "bit", "size", "the", "its",
                                      "their", "in")]
    if not t:
        return None
    if len(t) >= 3 and t[1] == "times" and _number(t[0]) is not None and t[2] in _SIZE_WORDS:
        return _number(t[0]) if _SIZE_WORDS[t[2]] > 1 else 1.0 / _number(t[0])      # type: ignore[operator]
    if len(t) >= 3 and t[0] in _NUMBER_WORDS and t[1] == "as" and t[2] in _SIZE_WORDS:
        return _NUMBER_WORDS[t[0]]
    if len(t) >= 4 and _number(t[0]) is not None and t[1] == "times" and t[2] == "as" and t[3] in _SIZE_WORDS:
        return _number(t[0])
    if t == ["half"]:
        return 0.5
    if len(t) == 1 and t[0] in _SIZE_WORDS:
        return _SIZE_WORDS[t[0]]
    return None


def _make_size(reader: Any, toks: list[str]) -> list[dict] | None:
    found = _targets_or_none(reader, toks[1:])
    if found is None:
        return None
    targets, k = found
    factor = _size_factor(toks[1 + k:])
    if factor is None:
        return None
    return [{"op": "scale", "targets": targets, "factor": factor}]


AXIS_READERS.on("make", "get")(_make_size)


@AXIS_READERS.on("enlarge", "grow", "shrink", "scale", "resize")
def _resize(reader: Any, toks: list[str]) -> list[dict] | None:
    targets, k = reader._targets(toks[1:])
    rest = [w for w in toks[1 + k:] if w not in ("by", "a", "factor", "of", "to", "times")]
    factor = {"shrink": 0.6}.get(toks[0], 1.6)
    if rest:
        n = _number(rest[0])
        if n is None or n <= 0:
            raise reader.fail(f"expected a size factor after {toks[0]!r} (e.g. '{toks[0]} the ball by 2')")
        factor = n if toks[0] != "shrink" or n < 1 else 1.0 / n
    return [{"op": "scale", "targets": targets, "factor": factor}]


# ----------------------------------------------------------------- swap
@AXIS_READERS.on("replace", "swap", "exchange", "substitute")
def _replace(reader: Any, toks: list[str]) -> list[dict] | None:
    targets, k = reader._targets(toks[1:])
    j = 1 + k
    if j >= len(toks) or toks[j] not in ("with", "by", "for"):
        raise reader.fail(f"expected '{toks[0]} the X with a Y'")
    new = _new_object(toks, j + 1)
    if new is None:
        raise reader.fail(f"expected an object to {toks[0]} it with (e.g. 'with a cube'), found "
                          f"{' '.join(toks[j + 1:])!r}")
    return [{"op": "swap", "targets": targets, "category": new[0], "color": new[1]}]


@AXIS_READERS.on("turn", "change", "transform", "convert", "morph")
def _turn_into(reader: Any, toks: list[str]) -> list[dict] | None:
    if "into" not in toks:
        return None
    found = _targets_or_none(reader, toks[1:])
    if found is None:
        return None
    targets, k = found
    j = 1 + k
    if j >= len(toks) or toks[j] != "into":
        return None
    new = _new_object(toks, j + 1)
    if new is None:
        return None                                   # "turn the ball into red": a recolour
    return [{"op": "swap", "targets": targets, "category": new[0], "color": new[1]}]


# ----------------------------------------------------------------- insertion
def _relation(toks: Sequence[str], j: int) -> tuple[str, int] | None:
    """(relation, index of the anchor) for "next to", "beside", "near", "behind", "in front of",
    "between the camera and"."""
    rest = list(toks[j:])
    for words, rel in ((["next", "to"], "next_to"), (["beside"], "next_to"), (["near"], "next_to"),
                       (["by"], "next_to"), (["behind"], "behind"), (["in", "front", "of"], "in_front"),
                       (["before"], "in_front")):
        if rest[:len(words)] == words:
            return rel, j + len(words)
    if rest[:1] == ["between"]:
        try:
            a = rest.index("and")
        except ValueError:
            return None
        left, right = rest[1:a], rest[a + 1:]
        if "camera" in left:
            return "occluding", j + a + 1
        if "camera" in right:
            return "occluding", j + 1
    return None


@AXIS_READERS.on("add", "put", "place", "insert")
def _insert(reader: Any, toks: list[str]) -> list[dict] | None:
    new = _new_object(toks, 1)
    if new is None:
        if toks[0] in ("put", "place", "insert") and not _scene_target(toks[1:]):
            raise reader.fail(f"expected '{toks[0]} a <object> next to / behind / between the camera and the X'")
        return None
    category, color, j = new
    if j >= len(toks):
        return [{"op": "insert", "targets": [], "category": category, "color": color, "relation": "next_to"}]
    rel = _relation(toks, j)
    if rel is None:
        raise reader.fail(f"expected where to put the {category} ('next to the X', 'behind the X', 'between the "
                          f"camera and the X'), found {' '.join(toks[j:])!r}")
    relation, a = rel
    anchor = [w for w in toks[a:] if w not in ("the", "camera", "and")] if relation == "occluding" else toks[a:]
    targets, _ = reader._targets(["the"] + anchor if anchor and anchor[0] not in ("the", "it") else anchor)
    return [{"op": "insert", "targets": targets, "category": category, "color": color, "relation": relation}]


# ----------------------------------------------------------------- lighting
def _light_change(words: Sequence[str]) -> dict | None:
    for w in words:
        if w in _LIGHT_BRIGHTNESS:
            return {"op": "light", "mode": "brightness", "factor": _LIGHT_BRIGHTNESS[w]}
        if w in _LIGHT_TEMPERATURE:
            return {"op": "light", "mode": "temperature", "amount": _LIGHT_TEMPERATURE[w]}
    if "from" in words:
        k = list(words).index("from")
        for w in words[k + 1:]:
            if w in _FROM_DIRECTIONS:
                return {"op": "light", "mode": "direction", "direction_world": _FROM_DIRECTIONS[w]}
    return None


@AXIS_READERS.on("make", "set", "change", "turn")
def _make_light(reader: Any, toks: list[str]) -> list[dict] | None:
    head = [w for w in toks[1:4] if w not in ("the", "scene", "'s")]
    if not head or head[0] not in _LIGHT_NOUNS:
        return None
    d = _light_change(toks[2:])
    if d is None:
        raise reader.fail("expected how the light changes ('brighter', 'dimmer', 'warmer', 'cooler', "
                          "'come from the left')")
    return [dict(d, targets=[])]


@AXIS_READERS.on("dim", "brighten", "warm", "cool")
def _light_verb(reader: Any, toks: list[str]) -> list[dict] | None:
    if not any(w in _LIGHT_NOUNS for w in toks[1:4]):
        return None
    if toks[0] in ("dim", "brighten"):
        return [{"op": "light", "targets": [], "mode": "brightness", "factor": 0.6 if toks[0] == "dim" else 1.4}]
    return [{"op": "light", "targets": [], "mode": "temperature", "amount": 0.6 if toks[0] == "warm" else -0.6}]


@AXIS_READERS.on("light", "illuminate", "relight")
def _light_from(reader: Any, toks: list[str]) -> list[dict] | None:
    d = _light_change(toks[1:])
    if d is None:
        raise reader.fail("expected where the light comes from ('light the scene from the left')")
    return [dict(d, targets=[])]


# ----------------------------------------------------------------- sky, texture, setting
@AXIS_READERS.on("make", "change", "set", "turn", "switch")
def _sky(reader: Any, toks: list[str]) -> list[dict] | None:
    if toks[1:3] != ["the", "sky"] and toks[1:2] != ["sky"]:
        return None
    names = [_SKY_WORDS[w] for w in toks[2:] if w in _SKY_WORDS]
    if not names:
        return None                                    # "make the sky blue": a recolour
    return [{"op": "sky", "targets": [], "name": names[0]}]


@AXIS_READERS.on("make", "give", "turn", "texture")
def _texture(reader: Any, toks: list[str]) -> list[dict] | None:
    names = [_TEXTURE_WORDS[w] for w in toks[2:] if w in _TEXTURE_WORDS]
    if not names or (toks[0] == "make" and toks[1:3] == ["the", "sky"]):
        return None
    found = _targets_or_none(reader, toks[1:])
    if found is None:
        return None
    targets, k = found
    tail = [w for w in toks[1 + k:] if w not in ("a", "an", "look", "be", "texture", "pattern", "finish", "material",
                                                  "surface", "with", "polka", "dots", "dot", "stripes", "checks")]
    if len(tail) != 1 or tail[0] not in _TEXTURE_WORDS:
        return None
    return [{"op": "texture", "targets": targets, "name": _TEXTURE_WORDS[tail[0]]}]


@AXIS_READERS.on("move", "set", "put", "place", "change", "switch", "relocate", "transport")
def _setting(reader: Any, toks: list[str]) -> list[dict] | None:
    if not _scene_target(toks[1:]):
        return None
    names = [SETTING_WORDS[w] for w in toks[2:] if w in SETTING_WORDS and w not in ("sky", "ground")]
    if not names:
        return None
    return [{"op": "setting", "targets": [], "name": names[0]}]


# ----------------------------------------------------------------- camera view
def _metres(words: Sequence[str], default: float) -> float:
    for i, w in enumerate(words):
        n = _number(w) if w not in ("a", "an") else None
        if n is not None:
            unit = words[i + 1] if i + 1 < len(words) else "m"
            return n * _UNITS.get(unit, 1.0)
    return default


@AXIS_READERS.on("widen", "narrow", "increase", "decrease", "reduce", "make", "change")
def _fov(reader: Any, toks: list[str]) -> list[dict] | None:
    words = list(toks)
    if not (("field" in words and "view" in words) or "fov" in words):
        return None
    factor = {"widen": 1.3, "increase": 1.3, "narrow": 0.75, "decrease": 0.75, "reduce": 0.75}.get(toks[0])
    if "wider" in words or "larger" in words or "bigger" in words:
        factor = 1.3
    if "narrower" in words or "smaller" in words:
        factor = 0.75
    if factor is None:
        raise reader.fail("expected 'widen' or 'narrow' the field of view")
    for i, w in enumerate(words):
        n = _number(w) if w not in ("a", "an") else None
        if n is not None and i + 1 < len(words) and words[i + 1] in ("percent", "%"):
            factor = 1.0 + n / 100.0 if factor > 1 else 1.0 - n / 100.0
    return [{"op": "view", "targets": [], "factor": factor}]


@AXIS_READERS.on("raise", "lower", "lift", "move")
def _height(reader: Any, toks: list[str]) -> list[dict] | None:
    if "camera" not in toks[1:4]:
        return None
    rest = toks[toks.index("camera") + 1:]
    if toks[0] == "move":
        if not rest or rest[0] not in ("up", "down", "higher", "lower"):
            return None
        sign = 1.0 if rest[0] in ("up", "higher") else -1.0
    else:
        sign = -1.0 if toks[0] == "lower" else 1.0
    return [{"op": "view", "targets": [], "amount": sign * _metres(rest, 0.5)}]


# ----------------------------------------------------------------- sensor
def _amount(words: Sequence[str]) -> float:
    return next((_AMOUNTS[w] for w in words if w in _AMOUNTS), 0.5)


@AXIS_READERS.on("add", "apply", "introduce")
def _sensor_add(reader: Any, toks: list[str]) -> list[dict] | None:
    names = [_SENSOR_WORDS[w] for w in toks[1:] if w in _SENSOR_WORDS]
    if not names:
        return None
    return [{"op": "sensor", "targets": [], "name": names[0], "amount": _amount(toks)}]


@AXIS_READERS.on("blur", "compress", "degrade")
def _sensor_verb(reader: Any, toks: list[str]) -> list[dict] | None:
    if not any(w in _SENSOR_NOUNS for w in toks[1:]):
        return None
    name = {"blur": "blur", "compress": "jpeg", "degrade": "noise"}[toks[0]]
    return [{"op": "sensor", "targets": [], "name": name, "amount": _amount(toks)}]


@AXIS_READERS.on("make")
def _sensor_make(reader: Any, toks: list[str]) -> list[dict] | None:
    if not any(w in _SENSOR_NOUNS for w in toks[1:4]) or "camera" in toks[1:3] and "move" in toks:
        return None
    names = [_SENSOR_WORDS[w] for w in toks[2:] if w in _SENSOR_WORDS]
    if not names:
        return None
    return [{"op": "sensor", "targets": [], "name": names[0], "amount": _amount(toks)}]


# ----------------------------------------------------------------- time offset
def _seconds(reader: Any, words: Sequence[str]) -> float:
    for i, w in enumerate(words):
        n = _number(w) if w not in ("a", "an") or (i + 1 < len(words) and words[i + 1] in _SECONDS) else None
        if n is not None and i + 1 < len(words) and words[i + 1] in _SECONDS:
            return n
    raise reader.fail("expected a time offset in seconds (e.g. 'by 1 second', '2 seconds later')")


@AXIS_READERS.on("delay", "postpone", "advance")
def _delay(reader: Any, toks: list[str]) -> list[dict] | None:
    r = [w for w in toks[1:] if w not in ("motion", "movement", "start", "of", "trajectory")]
    targets, k = reader._targets(r)
    s = _seconds(reader, r[k:])
    return [{"op": "delay", "targets": targets, "seconds": -s if toks[0] == "advance" else s}]


@AXIS_READERS.on("make", "have", "let", "start")
def _start_later(reader: Any, toks: list[str]) -> list[dict] | None:
    if not any(w in ("later", "earlier", "sooner", "late", "early") for w in toks):
        return None
    r = [w for w in toks[1:] if w not in ("motion", "movement", "of", "moving", "to", "start", "starts", "begin",
                                          "its", "their")]
    found = _targets_or_none(reader, r)
    if found is None:
        return None
    targets, k = found
    tail = r[k:]
    s = _seconds(reader, tail)
    return [{"op": "delay", "targets": targets, "seconds": -s if any(w in ("earlier", "sooner", "early")
                                                                      for w in tail) else s}]


AXIS_VERBS = AXIS_WORDS["verbs"]
