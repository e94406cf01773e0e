"""Rule-based command parser (the offline default): text -> `Plan`.

How a command is read
---------------------
1. Normalise and tokenise (lower case, hyphens, possessives, "2x" -> "2 times"), repair typos one
   edit away from a parser word (never a real English word: "bull" stays "bull").
2. Split into segments at sentence ends and at "then" / "after that" / "afterwards" / "finally".
3. A segment is an *edit* when it starts (after "please", "now", "can you"...) with an edit verb
   ("make the bus yellow", "delete the ball", "reverse its motion", "pan left"), or has the form
   "X should/must/is now ...", or continues a description without a subject ("... then stops").
   Otherwise it is a *generate* description: subject noun phrases, their verb, direction and path
   phrases, landmarks, a setting, and a camera clause ("while the camera circles the table").
   Consecutive generate segments merge into one generate plan; edits after it go to `plan.then`
   (one edit plan per segment). A description after an edit is an error.
4. Nouns: vocabulary first, else embedding grounding (`grounding.py`).

Decisions worth knowing
-----------------------
- Objects: one `ObjectSpec` per noun phrase, `count` for plurals ("two balls": count 2; a plural
  without number or a collective "a herd of cows": count 3). "the X" naming an object already in
  the plan refers to it; "a X" adds a new one (named "X_2"...).
- Landmarks: "to/towards/into/onto the X" -> motion end, "from the X" -> start, "around the X" ->
  circle centre; "past/near/next to/with ... the X" adds a static object. A landmark that is not
  yet an object of the plan is added as a static object (no motion); the generator places it.
- Settings: the first setting word (water, road, tabletop, snow, grass, sky, sand, room...) in the
  text; otherwise the habitat of the first object that has one (fish -> water, car -> road);
  otherwise "ground". "table" after a locative preposition ("on/across the table") or as what the
  camera circles is the tabletop setting, not an object; as a subject, with a colour/count, or as a
  motion's start/end it is an object.
- Pronouns "it/its/them/they" refer to the most recent subject or edit target (landmarks only when
  nothing else was named). With a scene and no antecedent, "it" is the scene's only non-background
  object, else an error.
- Edits without a scene keep their targets as written with a grounded category (``objects`` empty),
  unless ``require_scene=True``; a pronoun with nothing to refer to is always an error.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any, Sequence

from ..errors import CommandError
from .colors import COLOR_MODIFIERS, MODIFIER_SYNONYMS, color_rgb, match_color
from .grounding import (ALL_WORDS, CAMERA_WORDS, SceneItem, ground_noun, ground_noun_vocabulary,
                        resolve_in_scene, scene_items)
from .lexicon import (AUX, CLOCKWISE_WORDS, COLLECTIVE_NOUNS, DIRECTION_WORDS, DIRECTIONS, FAR_WORDS, NUMBER_WORDS,
                      PLURAL_DEFAULT_COUNT, SIZE_WORDS, SPEED_PHRASES, SPEED_VERBS, VERBS, VIEWER_WORDS,
                      correct_typo, lexicon_words, vec_norm, verb_info)
from .plan import MAX_COUNT, CameraSpec, ColorSpec, EditOp, MotionSpec, ObjectSpec, Plan, Target, edit_op
from .vocabulary import CATEGORIES, DEFAULT_SETTING, noun_to_category, singular, word_to_setting

__all__ = ["parse_rules", "tokenize", "MAX_TEXT_CHARS", "EXAMPLES"]

MAX_TEXT_CHARS = 2000
EXAMPLES = ('"a red ball bounces from right to left"', '"a red cube moves to the plate while the camera circles '
            'the table"', '"make the bus yellow"', '"delete the ball"', '"reverse its motion"')

# -- tokens ------------------------------------------------------------------------------------------

_COMPOUNDS = {"zig-zag": "zigzag", "zig zag": "zigzag", "counter-clockwise": "counterclockwise",
              "counter clockwise": "counterclockwise", "anti-clockwise": "anticlockwise",
              "anti clockwise": "anticlockwise", "north-east": "northeast", "north-west": "northwest",
              "south-east": "southeast", "south-west": "southwest", "north east": "northeast",
              "north west": "northwest", "south east": "southeast", "south west": "southwest",
              "back-and-forth": "back and forth", "to-and-fro": "to and fro", "get rid of": "getridof",
              "a lot": "alot", "colour": "color", "colours": "colors", "coloured": "colored",
              "grey": "grey", "aeroplane": "airplane", "towards": "toward", "afterwards": "afterward"}
_COMPOUND_RE = re.compile(r"\b(" + "|".join(re.escape(k) for k in sorted(_COMPOUNDS, key=len, reverse=True)) + r")\b")
_TOKEN_RE = re.compile(r"-?\d+(?:\.\d+)?|[a-z]+(?:'[a-z]+)?|[.,;!?:]")
_NT = {"don't": ("do", "not"), "doesn't": ("does", "not"), "didn't": ("did", "not"), "isn't": ("is", "not"),
       "aren't": ("are", "not"), "won't": ("will", "not"), "can't": ("can", "not"), "cannot": ("can", "not"),
       "let's": ("let", "us"), "i'd": ("i", "would"), "it'll": ("it", "will"), "shouldn't": ("should", "not")}
_ITS_NEXT = {"motion", "movement", "direction", "color", "speed", "path", "trajectory", "course", "way", "velocity",
             "heading", "colors", "hue"}


def tokenize(text: str) -> list[str]:
    """Lower-cased word, number and punctuation tokens with the parser's normalisations."""
    t = text.lower()
    t = (t.replace("\u2019", "'").replace("\u2018", "'").replace("\u201c", '"').replace("\u201d", '"')
         .replace("\u2014", " , ").replace("\u2013", " , ").replace("`", "'"))
    t = re.sub(r"(\d)\s*x\b", r"\1 times", t)
    t = re.sub(r"(\d)\s*%", r"\1 percent", t)
    t = _COMPOUND_RE.sub(lambda m: _COMPOUNDS[m.group(1)], t)
    t = re.sub(r"(?<=[a-z])-(?=[a-z])", " ", t)
    out: list[str] = []
    raw = _TOKEN_RE.findall(t)
    for i, w in enumerate(raw):
        if w in _NT:
            out.extend(_NT[w])
        elif w == "it's":
            nxt = raw[i + 1] if i + 1 < len(raw) else ""
            out.extend(["its"] if nxt in _ITS_NEXT else ["it", "is"])
        elif w.endswith("'s") and len(w) > 2:
            out.extend([w[:-2], "'s"])
        elif w.endswith("s'") and len(w) > 2:
            out.extend([w[:-1], "'s"])
        elif "'" in w:
            out.append(w.replace("'", ""))
        else:
            out.append(w)
    return [_COMPOUNDS.get(w, w) for w in out]


# -- word classes ----------------------------------------------------------------------------------------

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
_EDIT_STOP = {"make", "turn", "paint", "recolor", "recolour", "dye", "tint", "change", "delete", "remove", "erase",
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
_PREAMBLE_1 = {"please", "now", "and", "also", "then", "next", "finally", "so", "ok", "okay", "just", "kindly",
               "afterward", "after", "later", "lastly", "additionally", "first", "second", "third"}
_PREAMBLE_N = [("can", "you"), ("could", "you"), ("would", "you"), ("will", "you"), ("i", "want", "you", "to"),
               ("i", "would", "like", "you", "to"), ("i", "d", "like", "you", "to"), ("let", "us"),
               ("go", "ahead", "and"), ("try", "to"), ("after", "that"), ("i", "need", "you", "to"),
               ("lets",), ("we", "should"), ("you", "should")]
_SEG_PUNCT = {".", "!", "?", ";"}
_SPEED_WORDS_1 = {p[0] for p in SPEED_PHRASES if len(p) == 1}
_VIEWER = set(VIEWER_WORDS)


def _is_adverb(w: str) -> bool:
    return len(w) >= 6 and w.endswith("ly") and noun_to_category(w) is None and w not in COLLECTIVE_NOUNS


def _is_number(w: str) -> bool:
    return bool(re.fullmatch(r"-?\d+(?:\.\d+)?", w))


def _stop_word(w: str) -> bool:
    """Words that end a noun phrase."""
    return (w in VERBS or w in AUX or w in PREPS or w in CONJ or w in RELATIVE or w in _SEG_PUNCT or w == ","
            or w in DIRECTION_WORDS or w in CLOCKWISE_WORDS or w in ("'s", "not", "than", "of", "until", "when",
                                                                      "if", "because", "before", "there", "here",
                                                                      "now", "again", "instead", "too")
            or w in STATIONARY or _is_adverb(w) or w in _EDIT_STOP)


# -- noun phrases -------------------------------------------------------------------------------------


@dataclass
class _NP:
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


def _match_phrase(toks: Sequence[str], i: int, table: dict[tuple[str, ...], Any]) -> tuple[Any, int] | None:
    for k in (5, 4, 3, 2, 1):
        key = tuple(toks[i:i + k])
        if len(key) == k and key in table:
            return table[key], k
    return None


_NUMBER_PHRASES = {tuple(k.split()): v for k, v in NUMBER_WORDS.items()}
# number words that combine into compound numbers (no "a few" / "several")
_COMPOUND_NUMBER = {k: v for k, v in NUMBER_WORDS.items() if " " not in k and k not in (
    "single", "both", "several", "few", "some", "many", "multiple", "dozen")}
_SIZE_PHRASES = {tuple(k.split()): k for k in SIZE_WORDS}


def _number_at(toks: Sequence[str], i: int) -> tuple[int, int] | None:
    if i >= len(toks):
        return None
    w = toks[i]
    if _is_number(w):
        v = float(w)
        if v != int(v):
            raise CommandError(f"Could not understand the count {w!r}: expected a whole number of objects")
        value, used = int(v), 1
    else:
        hit = _match_phrase(toks, i, _NUMBER_PHRASES)
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


def _parse_np(toks: Sequence[str], i: int, edit: bool = False) -> _NP | None:
    """A noun phrase starting at i, or None when none starts there."""
    n = len(toks)
    if i >= n:
        return None
    np_ = _NP(start=i, end=i, words=[])
    j = i
    w = toks[j]
    if w in PRONOUNS and w not in ("both", "its", "their", "his", "her"):
        np_.kind, np_.head, np_.end, np_.words = "pronoun", w, j + 1, [w]
        np_.plural = w in ("them", "they", "themselves")
        return np_
    if w in ("its", "their") and (j + 1 >= n or _stop_word(toks[j + 1]) or toks[j + 1] in (
            "motion", "movement", "direction", "speed", "color", "path", "trajectory")):
        np_.kind, np_.head, np_.end, np_.words = "pronoun", w, j + 1, [w]
        np_.plural = w == "their"
        return np_
    num = None
    if w in ("a", "an") and (j + 1 < n) and _match_phrase(toks, j, _NUMBER_PHRASES) is None:
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
    num = _number_at(toks, j)
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
            if (collected and not known_head and nxt and not _stop_word(nxt) and nxt not in DETS
                    and _number_at(toks, j + 1) is None and "," not in nxt):
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
            if after is not None and (not _stop_word(after) or (after == "," and not edit) or noun_to_category(after)
                                      or (word_to_setting(after) and np_.det is not None)) and after != "'s":
                np_.color = np_.color or (col[0], col[1])  # "tomato red": the first colour names it
                collected.extend(range(j, j + col[2]))
                j += col[2]
                continue
            if collected and (after is None or _stop_word(after)):
                break  # "make the vehicle blue": a trailing colour is the complement, not the noun
        if w in INTENSIFIERS and j + 1 < n and (toks[j + 1] in _SPEED_WORDS_1 or " ".join(toks[j:j + 2]) in SIZE_WORDS):
            pass  # "very small" / "very fast": let the phrase tables below see both words
        elif _stop_word(w) and not (w in _SPEED_WORDS_1 and j + 1 < n and not _stop_word(toks[j + 1])) and not (
                (word_to_setting(w) or noun_to_category(w)) and (
                    (not collected and np_.det is not None)
                    or (collected and (j + 1 >= n or toks[j + 1] in VERBS or toks[j + 1] in AUX)))):
            # nouns that are also verbs: "the park", "a yellow taxi speeds"
            break
        sz = _match_phrase(toks, j, _SIZE_PHRASES)
        if sz is not None and j + sz[1] < n and (not _stop_word(toks[j + sz[1]]) or toks[j + sz[1]] == ","):
            np_.size = sz[0]
            np_.scale = SIZE_WORDS[sz[0]]
            collected.extend(range(j, j + sz[1]))
            j += sz[1]
            continue
        sp = _match_phrase(toks, j, SPEED_PHRASES)
        if sp is not None and j + sp[1] < n and not _stop_word(toks[j + sp[1]]):
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
    unknown = [k for k in collected if not _known_word(toks[k])]
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
    elif head in _VIEWER or head in ("viewer", "camera"):
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


def _known_word(w: str) -> bool:
    return (w in lexicon_words() or w in DETS or w in PREPS or w in CONJ or w in AUX or w in INTENSIFIERS
            or match_color([w]) is not None or _is_number(w))


# -- motion phrases ------------------------------------------------------------------------------------


@dataclass
class _Pred:
    verbs: list[tuple[str, str]] = field(default_factory=list)  # (base, kind)
    dirs: list[tuple[tuple[float, float, float], str]] = field(default_factory=list)
    from_side: tuple[tuple[float, float, float], str] | None = None
    to_side: tuple[tuple[float, float, float], str] | None = None
    path: str | None = None
    clockwise: bool | None = None
    speed: float | None = None
    speed_word: str | None = None
    factor: float | None = None  # relative speed ("twice as fast"), edits
    start: _NP | None = None
    end: _NP | None = None
    around: _NP | None = None
    statics: list[_NP] = field(default_factory=list)
    settings: list[str] = field(default_factory=list)
    stationary: bool = False
    in_place: bool = False
    negated: bool = False
    oscillate_axis: tuple[float, float, float] | None = None
    oscillate: bool = False
    reverse: bool = False
    unknown: list[str] = field(default_factory=list)
    with_nps: list[_NP] = field(default_factory=list)

    def has_motion(self) -> bool:
        return bool([v for v in self.verbs if v[1] != "aux"] or self.dirs or self.from_side or self.to_side
                    or self.path or self.clockwise is not None or self.speed is not None or self.end
                    or self.start or self.around or self.stationary or self.oscillate)


_SIDE_WORDS = {"left": "left", "right": "right", "top": "up", "bottom": "down", "north": "north", "south": "south",
               "east": "east", "west": "west", "northeast": "northeast", "northwest": "northwest",
               "southeast": "southeast", "southwest": "southwest", "up": "up", "down": "down", "sky": "up",
               "ground": "down", "upper": "up", "lower": "down", "leftside": "left", "rightside": "right"}
_SIDE_TAIL = {"side", "edge", "end", "part", "corner", "of", "frame", "screen", "hand", "bank", "half"}


def _side_at(toks: Sequence[str], i: int) -> tuple[str, int] | None:
    """A side such as "left", "the left", "the left side", "the top of the screen" at i."""
    j = i
    n = len(toks)
    if j < n and toks[j] == "the":
        j += 1
    if j < n and toks[j] in ("far", "very"):
        j += 1
    if j >= n or toks[j] not in _SIDE_WORDS:
        return None
    if toks[j] in ("sky", "ground") and j == i:  # "to sky" is not a side; "to the sky"/"to the ground" is
        return None
    side = _SIDE_WORDS[toks[j]]
    j += 1
    while j < n and toks[j] in _SIDE_TAIL | {"the", "screen", "frame", "image", "scene", "view"} and toks[j] != "to":
        if toks[j] == "of" and not (j + 1 < n and toks[j + 1] in ("the", "screen", "frame", "image", "scene", "view")):
            break
        j += 1
    return side, j - i


def _dir(name: str) -> tuple[float, float, float]:
    return DIRECTIONS[name]


class _PhraseScanner:
    """Reads verb, direction, path, speed and landmark phrases from a token span."""

    def __init__(self, toks: Sequence[str], edit: bool = False) -> None:
        self.toks = toks
        self.edit = edit

    def scan(self, i: int, end: int, pred: _Pred, boundary: Any = None) -> int:
        toks = self.toks
        while i < end:
            if boundary is not None and boundary(i):
                break
            w = toks[i]
            nxt = toks[i + 1] if i + 1 < end else ""
            # speed phrases (longest first), "twice as fast", "N times faster"
            k = self._relative_speed(i, end, pred)
            if k:
                i += k
                continue
            sp = _match_phrase(toks[:end], i, SPEED_PHRASES)
            if sp is not None:
                pred.speed, pred.speed_word = sp[0], " ".join(toks[i:i + sp[1]])
                i += sp[1]
                continue
            if w in ("faster", "quicker", "slower", "speedier") or (w in ("speed", "slow") and nxt in ("up", "down")):
                k = self._relative_speed(i, end, pred, allow_bare=True)
                if k:
                    i += k
                    continue
            if w == "not" or (w in ("never",)):
                pred.negated = True
                i += 1
                continue
            # sides: "from left to right", "left to right", "from the left", "to the left"
            if w == "from":
                side = _side_at(toks[:end], i + 1)
                if side is not None and not (i + 1 + side[1] < end and toks[i + 1 + side[1]] == "of"):
                    pred.from_side = (_dir(side[0]), " ".join(toks[i:i + 1 + side[1]]))
                    i += 1 + side[1]
                    continue
                if nxt in ("side",) and i + 3 < end and toks[i + 2] == "to" and toks[i + 3] == "side":
                    pred.oscillate, pred.oscillate_axis = True, (1.0, 0.0, 0.0)
                    i += 4
                    continue
                np_ = _parse_np(toks[:end], i + 1)
                if np_ is not None and np_.kind in ("category", "unknown"):
                    pred.start = np_
                    i = np_.end
                    continue
                if np_ is not None and np_.kind == "setting":
                    pred.settings.append(np_.category)
                    i = np_.end
                    continue
                if np_ is not None and np_.kind == "viewer":
                    pred.dirs.append((_dir("away"), "from the camera"))
                    i = np_.end
                    continue
                i += 1
                continue
            side = _side_at(toks[:end], i)
            if side is not None and w != "the" and i + side[1] < end and toks[i + side[1]] == "to" and w in (
                    "left", "right", "top", "bottom", "north", "south", "east", "west"):
                side2 = _side_at(toks[:end], i + side[1] + 1)
                if side2 is not None:
                    pred.from_side = (_dir(side[0]), w)
                    pred.to_side = (_dir(side2[0]), " ".join(toks[i:i + side[1] + 1 + side2[1]]))
                    i += side[1] + 1 + side2[1]
                    continue
            if w in ("to", "toward", "into", "onto") and nxt in ("each", "one") and i + 2 < end and toks[i + 2] in (
                    "other", "another"):
                i += 3
                continue
            if w in ("to", "toward", "into", "onto", "until", "reaching") or (w == "up" and nxt == "to"):
                if w == "up":
                    i += 1
                    w = "to"
                    nxt = toks[i + 1] if i + 1 < end else ""
                j = i + 1
                if j < end and toks[j] in ("and", "fro") and w == "to":
                    if toks[j] == "fro" or (j + 1 < end and toks[j + 1] == "fro"):
                        pred.oscillate = True
                        i = j + (1 if toks[j] == "fro" else 2)
                        continue
                side = _side_at(toks[:end], j)
                if side is not None and w in ("to", "toward", "until", "reaching"):
                    if pred.to_side is not None and pred.from_side is None:
                        pred.from_side = pred.to_side  # "moves left to right": second side is the end
                    if toks[j] in ("sky",) or (j + 1 < end and toks[j + 1] in ("sky",)):
                        pred.settings.append("sky")
                    pred.to_side = (_dir(side[0]), " ".join(toks[i:j + side[1]]))
                    i = j + side[1]
                    continue
                np_ = _parse_np(toks[:end], j)
                if np_ is not None and np_.kind == "viewer":
                    pred.dirs.append((_dir("toward"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                if np_ is not None and np_.head in FAR_WORDS:
                    pred.dirs.append((_dir("away"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                if np_ is not None and np_.kind == "setting":
                    pred.settings.append(np_.category)
                    if np_.category == "sky" and w in ("into", "toward", "to"):
                        pred.dirs.append((_dir("up"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                if np_ is not None and np_.kind in ("category", "unknown"):
                    pred.end = np_
                    i = np_.end
                    continue
                if np_ is not None and np_.kind == "camera":
                    pred.dirs.append((_dir("toward"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                i += 1
                continue
            if w == "away":
                j = i + 1
                if j < end and toks[j] == "from":
                    np_ = _parse_np(toks[:end], j + 1)
                    if np_ is not None and np_.kind in ("viewer", "camera"):
                        pred.dirs.append((_dir("away"), " ".join(toks[i:np_.end])))
                        i = np_.end
                        continue
                    if np_ is not None and np_.kind in ("category", "unknown"):
                        pred.start = np_
                        i = np_.end
                        continue
                pred.dirs.append((_dir("away"), "away"))
                i += 1
                continue
            if w in ("closer", "nearer") and nxt == "to":
                np_ = _parse_np(toks[:end], i + 2)
                if np_ is not None and np_.kind in ("viewer", "camera"):
                    pred.dirs.append((_dir("toward"), " ".join(toks[i:np_.end])))
                    i = np_.end
                    continue
                if np_ is not None and np_.kind in ("category", "unknown"):
                    pred.end = np_
                    i = np_.end
                    continue
            if w in ("around", "round") or (w == "in" and nxt in ("circles", "circle", "loops", "loop", "a")):
                k = self._around(i, end, pred)
                if k:
                    i += k
                    continue
            if w == "in" and nxt in ("place",):
                pred.in_place = True
                i += 2
                continue
            if w == "in" and nxt in ("a", "zigzags", "zigzag") and self._path_phrase(i, end, pred):
                i += self._path_phrase(i, end, pred)
                continue
            if w == "back" and nxt == "and" and i + 2 < end and toks[i + 2] in ("forth", "forward", "forwards"):
                pred.oscillate = True
                i += 3
                continue
            if w == "side" and nxt == "to" and i + 2 < end and toks[i + 2] == "side":
                pred.oscillate, pred.oscillate_axis = True, (1.0, 0.0, 0.0)
                i += 3
                continue
            if w in ("up", "left") and nxt == "and" and i + 2 < end and toks[i + 2] in ("down", "right"):
                pred.oscillate = True
                pred.oscillate_axis = (0.0, 0.0, 1.0) if w == "up" else (1.0, 0.0, 0.0)
                i += 3
                continue
            if w in ("backwards", "backward", "back") and self.edit:
                pred.reverse = True
                i += 1
                continue
            if w in ("opposite", "other") and nxt in ("way", "direction", "directions"):
                pred.reverse = True
                i += 2
                continue
            if w in CLOCKWISE_WORDS:
                pred.clockwise = CLOCKWISE_WORDS[w]
                i += 1
                continue
            if w in ("zigzag", "zigzags") and not verb_info(w):
                pred.path = "zigzag"
                i += 1
                continue
            if w in ("up", "down") and nxt in ("the", "a", "this", "that") and i + 2 < end:
                np_ = _parse_np(toks[:end], i + 1)
                if np_ is not None and np_.kind in ("setting", "category", "unknown"):
                    if np_.kind == "setting":
                        pred.settings.append(np_.category)
                    elif np_.kind == "category":
                        pred.statics.append(np_)
                    i = np_.end
                    continue
            if w in DIRECTION_WORDS and w not in ("top", "bottom", "sky", "closer", "nearer") or w in (
                    "closer", "nearer"):
                if w in ("right",) and nxt in ("now", "away"):
                    i += 2
                    continue
                pred.dirs.append((_dir(DIRECTION_WORDS[w]), w))
                i += 1
                continue
            if w in STATIONARY:
                pred.stationary = True
                i += 1
                continue
            vi = verb_info(w)
            if vi is not None:
                base, kind = vi
                pred.verbs.append((base, kind))
                if base in SPEED_VERBS and pred.speed is None:
                    pred.speed, pred.speed_word = SPEED_VERBS[base], w
                # direct objects: "circles the tree", "chases the cat", "crosses the road"
                if nxt and (nxt in DETS or noun_to_category(nxt) is not None or word_to_setting(nxt) is not None) \
                        and base in ("circle", "orbit", "chase", "follow", "approach", "reach", "leave", "cross",
                                     "pass", "traverse", "enter", "revolve", "loop", "climb", "descend"):
                    np_ = _parse_np(toks[:end], i + 1)
                    if np_ is not None:
                        if np_.kind == "setting":
                            pred.settings.append(np_.category)
                        elif np_.kind in ("category", "unknown"):
                            if base in ("circle", "orbit", "revolve", "loop"):
                                pred.around = np_
                            elif base in ("chase", "follow", "approach", "reach"):
                                pred.end = np_
                            elif base == "leave":
                                pred.start = np_
                            else:
                                pred.statics.append(np_)
                        elif np_.kind in ("viewer", "camera") and base == "approach":
                            pred.dirs.append((_dir("toward"), " ".join(toks[i:np_.end])))
                        i = np_.end
                        continue
                i += 1
                continue
            if w in LOCATIVE_PREPS or w == "with" or w == "next" or w == "in":
                j = i + 1
                if w == "next" and nxt == "to":
                    j = i + 2
                elif w == "in" and nxt == "front" and i + 2 < end and toks[i + 2] == "of":
                    j = i + 3
                elif w == "on" and nxt == "top" and i + 2 < end and toks[i + 2] == "of":
                    j = i + 3
                elif w == "out" and nxt == "of":
                    j = i + 2
                np_ = _parse_np(toks[:end], j)
                if np_ is not None:
                    pred.settings.extend(np_.settings)  # "a snowy field": the modifier is the more specific
                    if np_.kind == "setting" or (np_.head == "table" and w != "with" and np_.count is None
                                                 and np_.color is None):
                        pred.settings.append(np_.category if np_.kind == "setting" else "table")
                    elif np_.kind in ("category", "unknown") and not (np_.kind == "unknown" and w == "in"):
                        pred.statics.append(np_)
                        if w == "with":
                            pred.with_nps.append(np_)
                    i = np_.end
                    continue
                if w in ("on", "at", "in", "with") and j < end and word_to_setting(toks[j]):
                    pred.settings.append(word_to_setting(toks[j]))
                    i = j + 1
                    continue
                i += 1
                continue
            s = word_to_setting(w)
            if s is not None and noun_to_category(w) is None:
                pred.settings.append(s)
                i += 1
                continue
            if w in ("each", "one") and nxt in ("other", "another"):
                i += 2  # "towards each other": a relation between the subjects, not an object
                continue
            if (w in ("a", "an", "the", "two", "three", "some") or noun_to_category(w)) and not self.edit:
                np_ = _parse_np(toks[:end], i)  # an object of some verb ("a dog fetches a ball")
                if np_ is not None and np_.kind == "category" and np_.end > i:
                    pred.statics.append(np_)
                    i = np_.end
                    continue
            if w in AUX or w in INTENSIFIERS or w in RELATIVE or w in DETS or w in CONJ or w == ",":
                i += 1
                continue
            if not _known_word(w):
                pred.unknown.append(w)
            i += 1
        return i

    def _relative_speed(self, i: int, end: int, pred: _Pred, allow_bare: bool = False) -> int:
        """ "twice as fast", "half as fast", "3 times faster", "50 percent slower", "faster"..."""
        toks = self.toks
        w = toks[i]
        j = i
        factor: float | None = None
        if w in ("minus", "negative") and j + 1 < end and (_is_number(toks[j + 1]) or toks[j + 1] in NUMBER_WORDS):
            raise CommandError(f"Could not use a negative speed factor in {' '.join(toks[i:end])!r}: the factor "
                               f"must be > 0 (say 'reverse' to reverse a motion)")
        if w in ("twice", "double") and j + 2 < end and toks[j + 1] == "as" and toks[j + 2] in ("slow", "slowly"):
            factor, j = 0.5, j + 3  # "twice as slowly"
        elif w in ("twice", "double") and j + 2 < end and toks[j + 1] == "as" and toks[j + 2] in (
                "fast", "quickly", "quick", "rapidly"):
            factor, j = 2.0, j + 3
        elif w == "half" and j + 2 < end and toks[j + 1] == "as" and toks[j + 2] in ("fast", "quickly", "quick"):
            factor, j = 0.5, j + 3
        elif w in ("at", "to") and j + 2 < end and toks[j + 1] in ("half", "double", "twice", "triple") and toks[
                j + 2] in ("speed", "the"):
            factor = {"half": 0.5, "double": 2.0, "twice": 2.0, "triple": 3.0}[toks[j + 1]]
            j += 3
            if toks[j - 1] == "the" and j < end and toks[j] == "speed":
                j += 1
        elif w in ("half", "double", "triple") and j + 1 < end and toks[j + 1] in ("speed", "pace"):
            factor, j = {"half": 0.5, "double": 2.0, "triple": 3.0}[w], j + 2
        else:
            num = _number_at(toks[:end], j) if (_is_number(w) or w in NUMBER_WORDS) else None
            if num is not None and j + num[1] < end and toks[j + num[1]] in ("times", "percent"):
                value, k = num
                unit = toks[j + k]
                j2 = j + k + 1
                if j2 < end and toks[j2] == "as" and j2 + 1 < end and toks[j2 + 1] in ("fast", "quickly", "quick",
                                                                                     "slow", "slowly"):
                    slow = toks[j2 + 1] in ("slow", "slowly")
                    j2 += 2
                    if j2 < end and toks[j2] == "as":
                        j2 += 1
                elif j2 < end and toks[j2] in ("faster", "quicker", "slower", "more"):
                    slow = toks[j2] == "slower"
                    j2 += 1
                    if toks[j2 - 1] == "more" and j2 < end and toks[j2] in ("slowly", "quickly"):
                        slow = toks[j2] == "slowly"
                        j2 += 1
                elif unit == "times" and j2 < end and toks[j2] in ("the", "normal", "its", "their", "speed"):
                    slow = False
                    while j2 < end and toks[j2] in ("the", "normal", "its", "their", "original", "speed", "current"):
                        j2 += 1
                else:
                    return 0
                if unit == "percent":
                    factor = 1.0 + value / 100.0 * (-1 if slow else 1)
                else:
                    if value == 0:
                        factor = 0.0
                    else:
                        factor = 1.0 / value if slow else float(value)
                j = j2
            elif allow_bare or w in ("faster", "quicker", "slower", "speedier"):
                mod = 1.0
                if i >= 1 and toks[i - 1] in ("much", "alot", "far", "way", "lot"):
                    mod = 2.0
                elif i >= 1 and toks[i - 1] in ("bit", "little", "slightly", "somewhat", "tad"):
                    mod = 0.5
                if w in ("faster", "quicker", "speedier") or (w == "speed" and j + 1 < end and toks[j + 1] == "up"):
                    factor = {1.0: 2.0, 2.0: 3.0, 0.5: 1.25}[mod]
                elif w == "slower" or (w == "slow" and j + 1 < end and toks[j + 1] == "down"):
                    factor = {1.0: 0.5, 2.0: round(1 / 3, 6), 0.5: 0.8}[mod]
                else:
                    return 0
                j += 2 if w in ("speed", "slow") else 1
                if j < end and toks[j] == "than" and j + 1 < end:  # "faster than before/now"
                    j += 2
            else:
                return 0
        if factor is None:
            return 0
        if factor <= 0:
            raise CommandError(f"Could not use the speed change {' '.join(toks[i:j])!r}: the speed factor must be "
                               f"> 0 (say 'stop' to stop a motion)")
        pred.factor = round(factor, 6)
        return j - i

    def _around(self, i: int, end: int, pred: _Pred) -> int:
        toks = self.toks
        w = toks[i]
        if w in ("around", "round"):
            j = i + 1
            if j < end and toks[j] in ("in",):
                k = self._path_phrase(j, end, pred)
                pred.path = pred.path or "circle"
                return 1 + k
            if j < end and toks[j] in ("and",) and j + 1 < end and toks[j + 1] in ("around", "round"):
                pred.path = "circle"
                return 3
            np_ = _parse_np(toks[:end], j)
            if np_ is not None and np_.kind in ("category", "unknown"):
                pred.around = np_
                pred.path = "circle"
                return np_.end - i
            if np_ is not None and np_.kind in ("setting", "all"):
                if np_.kind == "setting":
                    pred.settings.append(np_.category)
                pred.path = "circle"
                return np_.end - i
            pred.path = "circle"
            return 1
        return self._path_phrase(i, end, pred)

    def _path_phrase(self, i: int, end: int, pred: _Pred) -> int:
        """ "in a circle", "in circles", "in a loop", "in a zigzag (pattern)", "in a straight line" """
        toks = self.toks
        if toks[i] != "in":
            return 0
        j = i + 1
        if j < end and toks[j] == "a":
            j += 1
        while j < end and toks[j] in ("big", "large", "small", "wide", "tight", "little", "circular", "straight",
                                      "zigzag", "wavy", "round"):
            j += 1
        if j >= end:
            return 0
        head = toks[j]
        words = toks[i + 1:j + 1]
        if head in ("circle", "circles", "loop", "loops", "ring") or (head in ("path", "motion", "pattern", "arc",
                                                                             "orbit") and "circular" in words):
            pred.path = "circle"
        elif head in ("zigzag", "zigzags") or (head in ("path", "pattern", "line", "motion") and "zigzag" in words):
            pred.path = "zigzag"
        elif head == "line" and "straight" in words:
            pred.path = pred.path or "straight"
        else:
            return 0
        j += 1
        if j < end and toks[j] in ("pattern", "path", "motion", "line", "shape"):
            j += 1
        return j - i


# -- the parser ------------------------------------------------------------------------------------------


@dataclass
class _Obj:
    name: str
    noun: str
    category: str
    color: ColorSpec | None = None
    size: str | None = None
    scale: float = 1.0
    count: int = 1
    grounding: str = "vocabulary"
    similarity: float | None = None
    landmark: bool = False


@dataclass
class _TargetDraft:
    text: str
    kind: str  # noun | pronoun | all | camera
    noun: str = ""
    color: tuple[str, tuple[float, float, float]] | None = None
    plural: bool = False


class _RuleParser:
    def __init__(self, text: str, scene: Any = None, require_scene: bool = False) -> None:
        self.text = text
        self.scene = scene
        self.require_scene = require_scene
        self.items: list[SceneItem] | None = scene_items(scene) if scene is not None else None
        self.objects: list[_Obj] = []
        self.motions: dict[str, dict] = {}
        self.camera: CameraSpec | None = None
        self.settings: list[str] = []
        self.salience: list[str] = []  # object names, most recent last
        self.scene_salience: list[list[SceneItem]] = []
        self._last_ground: dict[str, str] = {}  # edit target noun -> grounded category (no scene)
        self.generated = False

    # ---- entry -------------------------------------------------------------------------------------
    def parse(self) -> Plan:
        toks = tokenize(self.text)
        toks = [self._fix_typo(w) for w in toks]
        segments = _split_segments(toks)
        if not segments:
            raise CommandError(f"Could not understand {self.text!r}: no words found. Try e.g. " + ", ".join(EXAMPLES))
        edits: list[tuple[str, list[EditOp]]] = []
        for seg in segments:
            kind, seg2 = _classify(seg, after_generate=self.generated and not edits)
            if kind == "camera":
                kind = "generate" if (self.generated and not edits) else "edit"
                if kind == "edit":
                    seg2 = _camera_decl_to_edit(seg2)
            if kind == "generate":
                if edits:
                    raise CommandError(f"Could not understand {' '.join(seg)!r} after an edit: describe the scene "
                                       f"first, then the edits (e.g. 'a ball rolls left; then make it blue')")
                self._generate_segment(seg2)
                self.generated = True
            else:
                ops = self._edit_segment(seg2)
                edits.append((_detok(seg), ops))
        return self._build(edits)

    def _fix_typo(self, w: str) -> str:
        if not w.isalpha() or len(w) < 4 or _known_word(w):
            return w
        fixed = correct_typo(w)
        return _COMPOUNDS.get(fixed, fixed) if fixed is not None else w

    # ---- generate ------------------------------------------------------------------------------------
    def _generate_segment(self, toks: list[str]) -> None:
        toks, cam_spans = _extract_camera_clauses(toks)
        pending: _Pred | None = None
        i = 0
        n = len(toks)
        any_clause = False
        while i < n:
            while i < n and (toks[i] in CONJ or toks[i] in (",", "there", "is", "are", "we", "see", "you", "can",
                                                               "shows", "show", "with", "here")):
                i += 1
            if i >= n:
                break
            subjects: list[_NP] = []
            while i < n:
                np_ = _parse_np(toks, i)
                if np_ is None:
                    break
                subjects.append(np_)
                i = np_.end
                if i < n and toks[i] == "'s":
                    break
                if i < n and toks[i] in ("and", ",") and i + 1 < n:
                    j = i + 1
                    if toks[j] == "and":
                        j += 1
                    nxt = _parse_np(toks, j) if j < n else None
                    if nxt is not None and toks[j] not in VERBS:
                        i = j
                        continue
                break
            pred = _Pred()
            scanner = _PhraseScanner(toks)
            j = scanner.scan(i, n, pred, boundary=lambda k: _clause_boundary(toks, k))
            if j == i and not subjects:
                # nothing readable here: skip a word (it is reported if nothing at all is understood)
                pred.unknown.append(toks[i])
                i += 1
                continue
            if subjects and all(np_.kind == "unknown" and np_.det is None and np_.count is None
                                for np_ in subjects) and not (pred.verbs or pred.dirs or pred.from_side
                                                              or pred.to_side or pred.settings or pred.path):
                # unknown words with no article and nothing else understood: not a description
                i = max(j, i + 1)
                continue
            if i < n and subjects:
                _agreement(subjects, toks, i)
            if not subjects and not self.salience and pred.has_motion():
                pending = pred if pending is None else _merge_pred(pending, pred)  # "from right to left, a ball ..."
                i = j
                continue
            if pending is not None and subjects:
                pred = _merge_pred(pred, pending)
                pending = None
            any_clause = self._apply_clause(subjects, pred, toks) or any_clause
            i = j
        for span in cam_spans:  # after the objects, so that "circles the cat" finds the cat
            self._camera_clause(span, generate=True)
        if not any_clause and not cam_spans and not self.settings:
            raise CommandError(f"Could not understand {_detok(toks)!r}: expected a description such as "
                               + EXAMPLES[0] + " or an edit such as " + EXAMPLES[2])

    def _apply_clause(self, subjects: list[_NP], pred: _Pred, toks: list[str]) -> bool:
        settings = list(pred.settings)
        for np_ in subjects:
            settings.extend(np_.settings)
        objs: list[_Obj] = []
        for np_ in subjects:
            if np_.kind == "setting":
                if np_.head == "table" or np_.category:
                    settings.append(np_.category)
                continue
            if np_.kind in ("viewer", "camera", "generic"):
                continue
            if np_.kind == "all":
                continue
            if np_.kind == "pronoun":
                if not self.salience:
                    raise CommandError(f"Could not tell what {np_.head!r} refers to in {_detok(toks)!r}: name the "
                                       f"object first")
                objs.append(self._obj(self.salience[-1]))
                continue
            objs.append(self._object_from_np(np_, subject=True))
        self.settings.extend(settings)
        if not objs and pred.with_nps and pred.has_motion():
            # "an underwater scene with a fish swimming to the right"
            objs = [self._object_from_np(np_, subject=True) for np_ in pred.with_nps]
            pred.statics = [np_ for np_ in pred.statics if np_ not in pred.with_nps]
        if not objs:
            if pred.has_motion() and not settings and subjects == []:
                if self.salience and pred.verbs:  # subjectless continuation ("... and bounces")
                    objs = [self._obj(self.salience[-1])]
                else:
                    return False
            elif settings:
                return True
            else:
                return False
        for np_ in pred.statics:
            if np_.kind == "category" or (np_.kind == "unknown" and np_.head not in SPATIAL_NOUNS):
                try:
                    self._object_from_np(np_, subject=False, landmark=True)
                except CommandError:
                    if np_.kind == "category":
                        raise
                    # an incidental place word that is no object ("across the glassy surface"): skip it
        for key in ("start", "end", "around"):
            np_ = getattr(pred, key)
            if np_ is not None and np_.kind == "unknown" and np_.head in SPATIAL_NOUNS:
                setattr(pred, key, None)
        if not pred.has_motion():
            for o in objs:
                self._touch(o.name)
            return True
        speed = pred.speed
        speed_word = pred.speed_word
        if pred.factor is not None and speed is None:
            speed, speed_word = pred.factor, "relative"
        for np_ in subjects:
            if np_.speed is not None and speed is None:
                speed, speed_word = np_.speed
        direction = _combine_directions(pred, toks)
        path = _path_of(pred, direction)
        if path == "stop":
            direction = None
        start = self._landmark(pred.start) if pred.start is not None else None
        end_ = self._landmark(pred.end) if pred.end is not None else None
        around = self._landmark(pred.around) if pred.around is not None else None
        if path == "oscillate" and direction is None and pred.oscillate_axis is not None:
            direction = pred.oscillate_axis
        if path == "bounce" and pred.oscillate:
            direction = None
        for o in objs:
            if o.name in (start, end_, around):
                raise CommandError(f"Could not understand {_detok(toks)!r}: {o.noun!r} cannot move to or around itself")
            m = dict(target=o.name, path=path, direction_world=direction,
                     speed=speed if speed is not None else 1.0, speed_word=speed_word if speed is not None else None,
                     start=start, end=end_, around=around if path == "circle" else None,
                     clockwise=pred.clockwise if path == "circle" else None)
            old = self.motions.get(o.name)
            if old is not None:
                m = _merge_motion(old, m)
            self.motions[o.name] = m
            self._touch(o.name)
        return True

    def _touch(self, name: str) -> None:
        if name in self.salience:
            self.salience.remove(name)
        self.salience.append(name)

    def _obj(self, name: str) -> _Obj:
        for o in self.objects:
            if o.name == name:
                return o
        raise KeyError(name)

    def _object_from_np(self, np_: _NP, subject: bool, landmark: bool = False) -> _Obj:
        g = self._ground(np_)
        noun = singular(np_.head) if (np_.plural or np_.kind == "unknown") else np_.head
        if g.method == "vocabulary":
            noun = g.noun if noun_to_category(np_.head) and noun_to_category(np_.head)[1] else noun
        # coreference: "the ball" (or a bare noun) naming an object already in the plan
        if np_.det not in ("a", "an", "another") and np_.count is None and not np_.collective:
            for o in reversed(self.objects):
                if o.noun == noun or (o.category == g.category and np_.det in ("the", "this", "that")):
                    if np_.color is not None and o.color is not None and o.color.name != np_.color[0]:
                        continue
                    if np_.color is not None and o.color is None:
                        o.color = ColorSpec(*np_.color)
                    return o
        count = 1
        if np_.count is not None:
            count = np_.count
        elif np_.collective or (np_.plural and np_.kind in ("category", "unknown")):
            count = PLURAL_DEFAULT_COUNT
        if count < 1 or count > MAX_COUNT:
            raise CommandError(f"Could not generate {count} {noun}s: the count must be between 1 and {MAX_COUNT}")
        names = {o.name for o in self.objects}
        name = noun
        k = 2
        while name in names:
            name = f"{noun}_{k}"
            k += 1
        o = _Obj(name=name, noun=noun, category=g.category,
                 color=ColorSpec(*np_.color) if np_.color else None, size=np_.size, scale=np_.scale, count=count,
                 grounding=g.method, similarity=g.similarity, landmark=landmark)
        self.objects.append(o)
        return o

    def _ground(self, np_: _NP):
        if np_.kind == "category":
            hit = ground_noun_vocabulary(np_.head)
            if hit is not None:
                return hit
        head = singular(np_.head) if np_.plural else np_.head
        # unknown nouns are embedded with their descriptive words ("golden retriever", "toy sedan")
        mods = [w for w in np_.words[:-1] if w not in DETS and w not in (",", "'s", "of") and not _is_number(w)
                and w not in SIZE_WORDS and w not in INTENSIFIERS and w not in NUMBER_WORDS
                and w not in COLLECTIVE_NOUNS]
        return ground_noun(head, phrase=" ".join(mods[-2:] + [head]) if mods else None)

    def _landmark(self, np_: _NP) -> str:
        if np_.kind == "pronoun":
            if not self.salience:
                raise CommandError("Could not tell what a pronoun refers to: name the object")
            return self.salience[-1]
        o = self._object_from_np(np_, subject=False, landmark=True)
        return o.name

    def _camera_clause(self, toks: list[str], generate: bool) -> CameraSpec:
        cam = _read_camera(toks)
        target = None
        if cam.get("target_np") is not None:
            np_ = cam["target_np"]
            if np_.kind == "setting" or np_.head == "table":
                self.settings.append(np_.category if np_.kind == "setting" else "table")
            elif np_.kind in ("category", "unknown", "pronoun") and generate:
                target = self._landmark(np_)  # "the camera orbits it": the last subject
            elif np_.kind in ("category", "unknown"):
                target = np_
        for s in cam.get("settings", []):
            self.settings.append(s)
        spec = CameraSpec(motion=cam["motion"], direction=cam.get("direction"), speed=cam.get("speed", 1.0),
                          speed_word=cam.get("speed_word"), target=target if isinstance(target, str) else None)
        if generate:
            self.camera = spec
        return spec

    # ---- edits -------------------------------------------------------------------------------------------
    def _edit_segment(self, toks: list[str]) -> list[EditOp]:
        drafts = _EditReader(toks).read()
        ops: list[EditOp] = []
        for d in drafts:
            ops.append(self._finish_op(d, toks))
        return ops

    def _finish_op(self, d: dict, toks: list[str]) -> EditOp:
        targets = tuple(self._resolve(t, toks) for t in d.pop("targets", []))
        cam_target = d.pop("camera_target_np", None)
        if d["op"] == "camera":
            cam: CameraSpec = d["camera"]
            if cam_target is not None:
                name = None
                if cam_target.kind == "setting" or cam_target.head == "table":
                    name = None
                elif self.generated:
                    name = self._landmark(cam_target)
                elif self.items is not None:
                    hits = resolve_in_scene(singular(cam_target.head), self.items, cam_target.text)
                    name = hits[0].name
                else:
                    name = singular(cam_target.head)
                d["camera"] = CameraSpec(cam.motion, cam.direction, cam.speed, cam.speed_word, name)
            return edit_op(**d)
        end_np = d.pop("end_np", None)
        if end_np is not None:
            d["end"] = self._edit_landmark(end_np, toks)
        around_np = d.pop("around_np", None)
        if around_np is not None:
            d["around"] = self._edit_landmark(around_np, toks)
        return edit_op(targets=targets, **d)

    def _edit_landmark(self, np_: _NP, toks: list[str]) -> str:
        if self.generated:
            return self._landmark(np_)
        if self.items is not None:
            hits = resolve_in_scene(singular(np_.head), self.items, np_.text)
            return hits[0].name
        return singular(np_.head) if np_.kind != "pronoun" else self._pronoun_name(np_.head, toks)

    def _pronoun_name(self, word: str, toks: list[str]) -> str:
        if self.salience:
            return self.salience[-1]
        raise CommandError(f"Could not tell what {word!r} refers to in {_detok(toks)!r}: name the object")

    def _resolve(self, t: _TargetDraft, toks: list[str]) -> Target:
        if t.kind == "camera":
            return Target(text=t.text, noun="camera", category="camera")
        if self.generated:  # a compound command: targets are the plan's objects
            return self._resolve_in_plan(t, toks)
        if self.items is None:
            if self.require_scene:
                raise CommandError(f"Could not apply the edit {_detok(toks)!r}: there is no scene to edit (pass the "
                                   f"scene, or describe one first, e.g. 'a ball rolls left; then {_detok(toks)}')")
            if t.kind == "pronoun":
                if self.salience:
                    name = self.salience[-1]
                    g = self._last_ground.get(name)
                    return Target(text=t.text, noun=name, category=g)
                raise CommandError(f"Could not tell what {t.text!r} refers to in {_detok(toks)!r}: there is no scene "
                                   f"and no object named before it; name the object (e.g. 'make the ball blue')")
            if t.kind == "all":
                return Target(text=t.text, noun="*", category=None)
            g = ground_noun(t.noun, settings=True)
            self.salience.append(t.noun)
            self._last_ground[t.noun] = g.category
            return Target(text=t.text, noun=t.noun, category=g.category,
                          color=ColorSpec(*t.color) if t.color else None)
        # with a scene
        items = self.items
        if t.kind == "pronoun":
            if self.scene_salience:
                hits = self.scene_salience[-1]
            else:
                fg = [it for it in items if not it.background]
                if len(fg) != 1:
                    raise CommandError(f"Could not tell what {t.text!r} refers to in {_detok(toks)!r}: the scene has "
                                       f"{len(fg)} objects ({', '.join(it.name for it in fg) or 'none'}); name one")
                hits = fg
            return _target_from_hits(t.text, hits[0].name if len(hits) == 1 else hits[0].category, hits)
        noun = "*" if t.kind == "all" else t.noun
        hits = resolve_in_scene(noun, items, t.text, t.color[1] if t.color else None)
        self.scene_salience.append(hits)
        cat = None if noun == "*" else (hits[0].category if len({h.category for h in hits}) == 1 else None)
        return Target(text=t.text, noun=noun, category=cat, objects=tuple(h.name for h in hits),
                      object_ids=tuple(h.id for h in hits), color=ColorSpec(*t.color) if t.color else None)

    def _resolve_in_plan(self, t: _TargetDraft, toks: list[str]) -> Target:
        if t.kind == "pronoun":
            if not self.salience:
                raise CommandError(f"Could not tell what {t.text!r} refers to in {_detok(toks)!r}")
            if t.plural and len(self.salience) >= 2 and self._obj(self.salience[-1]).count == 1:
                names = [o.name for o in self.objects if not o.landmark] or [self.salience[-1]]
            else:
                names = [self.salience[-1]]
            objs = [self._obj(n) for n in names]
        elif t.kind == "all":
            objs = list(self.objects)
        else:
            sing = singular(t.noun)
            objs = [o for o in self.objects if o.noun in (t.noun, sing) or o.name in (t.noun, sing)]
            if not objs:
                g = ground_noun_vocabulary(t.noun) or ground_noun_vocabulary(sing)
                if g is not None:
                    objs = [o for o in self.objects if o.category == g.category]
            if not objs:
                items = [SceneItem(o.name, o.category, i) for i, o in enumerate(self.objects)]
                if not items:
                    raise CommandError(f"Could not find {t.text!r}: the command names no objects")
                hits = resolve_in_scene(t.noun, items, t.text)
                objs = [self._obj(h.name) for h in hits]
            if t.color is not None and len(objs) > 1:
                same = [o for o in objs if o.color is not None and o.color.name == t.color[0]]
                objs = same or objs
        for o in objs:
            self._touch(o.name)
        cats = {o.category for o in objs}
        noun = "*" if t.kind == "all" else (objs[0].noun if t.kind == "pronoun" else t.noun)
        return Target(text=t.text, noun=noun, category=cats.pop() if len(cats) == 1 and noun != "*" else None,
                      objects=tuple(o.name for o in objs), color=ColorSpec(*t.color) if t.color else None)

    # ---- assemble -----------------------------------------------------------------------------------
    def _build(self, edits: list[tuple[str, list[EditOp]]]) -> Plan:
        then = tuple(Plan(mode="edit", text=text, edits=tuple(ops)) for text, ops in edits)
        if not self.generated:
            if not then:
                raise CommandError(f"Could not understand {self.text!r}. Try e.g. " + ", ".join(EXAMPLES))
            head = then[0]
            return Plan(mode="edit", text=self.text, edits=head.edits, then=then[1:])
        objects = tuple(ObjectSpec(name=o.name, noun=o.noun, category=o.category, color=o.color, size=o.size,
                                   scale=o.scale, count=o.count, grounding=o.grounding, similarity=o.similarity)
                        for o in self.objects)
        motions = tuple(MotionSpec(**self.motions[o.name]) for o in self.objects if o.name in self.motions)
        if self.settings:
            setting, source = self.settings[0], "text"
        else:
            setting, source = DEFAULT_SETTING, "default"
            for o in self.objects:
                h = CATEGORIES[o.category].habitat
                if h is not None:
                    setting, source = h, "inferred"
                    break
        if not objects and source != "text":
            raise CommandError(f"Could not understand {self.text!r}: no object to generate. Try e.g. " + EXAMPLES[0])
        return Plan(mode="generate", text=self.text, objects=objects, motions=motions,
                    camera=self.camera or CameraSpec(), setting=setting, setting_source=source, then=then)




def _target_from_hits(text: str, noun: str, hits: list[SceneItem]) -> Target:
    cats = {h.category for h in hits}
    return Target(text=text, noun=noun, category=cats.pop() if len(cats) == 1 else None,
                  objects=tuple(h.name for h in hits), object_ids=tuple(h.id for h in hits))


def _merge_pred(dst: _Pred, src: _Pred) -> _Pred:
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
    return dst


def _agreement(subjects: list[_NP], toks: Sequence[str], i: int) -> None:
    """A noun that looks plural is singular when its verb is ("the buss is moving")."""
    w = toks[i]
    singular_verb = w in ("is", "was", "has", "does") or (w in VERBS and w.endswith("s") and w != VERBS[w])
    if singular_verb and len(subjects) == 1 and subjects[0].kind in ("unknown", "category") \
            and subjects[0].count is None and not subjects[0].collective:
        subjects[0].plural = False  # also "the busses is moving" (a typo either way: trust the verb)


def _merge_motion(old: dict, new: dict) -> dict:
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


def _combine_directions(pred: _Pred, toks: Sequence[str]) -> tuple[float, float, float] | None:
    parts: list[tuple[tuple[float, float, float], str]] = []
    if pred.from_side is not None and pred.to_side is not None:
        a, b = pred.from_side, pred.to_side
        v = vec_norm(tuple(y - x for x, y in zip(a[0], b[0])))
        if v is None or a[0] == b[0]:
            raise CommandError(f"Could not understand the direction in {_detok(toks)!r}: it goes from {a[1]!r} to "
                               f"{b[1]!r}, which is the same place; say e.g. 'from left to right'")
        parts.append((v, f"{a[1]} {b[1]}"))
    elif pred.from_side is not None:
        parts.append((tuple(-c + 0.0 for c in pred.from_side[0]), pred.from_side[1]))  # type: ignore[misc]
    elif pred.to_side is not None:
        parts.append(pred.to_side)
    parts.extend(pred.dirs)
    for base, kind in pred.verbs:
        if kind in ("up", "down"):
            parts.append((_dir(kind), base))
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
                raise CommandError(f"Could not understand the direction in {_detok(toks)!r}: {parts[x][1]!r} and "
                                   f"{parts[y][1]!r} contradict each other; give one direction")
    uniq: list[tuple[float, float, float]] = []
    for v, _ in parts:
        if v not in uniq:
            uniq.append(v)
    total = vec_norm(tuple(sum(v[i] for v in uniq) for i in range(3)))
    return total


def _path_of(pred: _Pred, direction: Any) -> str:
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


def _clause_boundary(toks: Sequence[str], k: int) -> bool:
    """Whether a new clause (with its own subject) starts at token k."""
    w = toks[k]
    if w in _SEG_PUNCT:
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
    np_ = _parse_np(toks, j)
    if np_ is None:
        return False
    if np_.kind in ("viewer",) or (np_.kind == "setting" and toks[j] not in DETS):
        return False
    # a new subject is followed by a verb (or the end: "... and a plate")
    e = np_.end
    while e < len(toks) and (toks[e] in ("and", ",") or toks[e] in DETS):
        nxt = _parse_np(toks, e + 1 if toks[e] in ("and", ",") else e)
        if nxt is None:
            break
        e = nxt.end
    if e >= len(toks) or toks[e] in _SEG_PUNCT:
        return w != "as"
    t = toks[e]
    return t in VERBS or t in AUX or t in STATIONARY or t == "," or _is_adverb(t) or t in _SPEED_WORDS_1


# -- segments and classification ---------------------------------------------------------------------


def _detok(toks: Sequence[str]) -> str:
    s = " ".join(toks)
    return s.replace(" 's", "'s").replace(" ,", ",")


def _split_segments(toks: list[str]) -> list[list[str]]:
    segs: list[list[str]] = []
    cur: list[str] = []
    i = 0
    n = len(toks)
    while i < n:
        w = toks[i]
        brk = 0
        if w in _SEG_PUNCT:
            brk = 1
        elif w == "then" and cur:
            brk = 1
        elif w in ("afterward", "finally", "lastly", "subsequently") and cur:
            brk = 1
        elif w == "after" and i + 1 < n and toks[i + 1] in ("that", "this", "which") and cur:
            brk = 2
        elif w == "next" and i + 1 < n and toks[i + 1] == "," and cur:
            brk = 2
        if brk:
            while cur and cur[-1] in ("and", ",", ":"):
                cur.pop()
            if cur:
                segs.append(cur)
            cur = []
            i += brk
            continue
        cur.append(w)
        i += 1
    while cur and cur[-1] in ("and", ",", ":"):
        cur.pop()
    if cur:
        segs.append(cur)
    out = []
    for s in segs:
        s = [w for w in s if w not in (":",)]
        while s and s[0] in (",", "and", "then", "so"):
            s = s[1:]
        if s:
            out.append(s)
    return out


def _skip_preamble(toks: list[str]) -> list[str]:
    changed = True
    while changed and toks:
        changed = False
        for pat in _PREAMBLE_N:
            if tuple(toks[:len(pat)]) == pat:
                toks = toks[len(pat):]
                changed = True
        if toks and toks[0] in _PREAMBLE_1 and len(toks) > 1 and not (toks[0] == "next" and toks[1] == "to"):
            toks = toks[1:]
            changed = True
        if toks and toks[0] == ",":
            toks = toks[1:]
            changed = True
    if toks and toks[-1] in ("please",):
        toks = toks[:-1]
    return toks


_MODALS = {"should", "must", "shall", "will", "needs", "need", "has", "have", "ought", "is", "are", "becomes",
           "become", "turns", "gets", "get"}
_CONTINUATIONS = {"stops": "stop", "halts": "stop", "freezes": "stop", "reverses": "reverse", "disappears": "remove",
                  "vanishes": "remove", "turns": "turn", "becomes": "make", "speeds": "speed", "slows": "slow",
                  "changes": "change", "accelerates": "accelerate", "decelerates": "decelerate"}


def _classify(seg: list[str], after_generate: bool) -> tuple[str, list[str]]:
    """ "generate", "edit" or "camera" (a camera-only description), and the segment to parse."""
    toks = _skip_preamble(list(seg))
    if not toks:
        return "edit", seg
    w = toks[0]
    if w in EDIT_VERBS and not (w in ("set",) and len(toks) > 1 and toks[1] == "of"):
        # "move the ball left" is an edit; "circle" etc. as imperative verbs are edits too
        return "edit", toks
    if w in ("i", "we") and len(toks) > 2 and toks[1] in ("want", "would", "need", "wish"):
        k = 2
        while k < len(toks) and toks[k] in ("like", "to", "the", "want"):
            if toks[k] == "the":
                break
            k += 1
        rest = toks[k:]
        if "to" in rest:
            t = rest.index("to")
            return "edit", ["make"] + rest[:t] + [x for x in rest[t + 1:] if x != "be"]
        return "edit", ["make"] + rest
    if after_generate and w in _CONTINUATIONS:
        base = _CONTINUATIONS[w]
        return "edit", [base, "it"] + toks[1:]
    # "the ball should be blue", "the bus is now yellow", "the car must move faster"
    for k in range(1, min(len(toks), 8)):
        t = toks[k]
        if t in _MODALS:
            np_ = _parse_np(toks, 0, edit=True)
            if np_ is None or np_.end != k and not (np_.end < k and toks[np_.end] in ("and", ",")):
                break
            rest = toks[k + 1:]
            if t in ("is", "are") and not (rest and rest[0] in ("now", "to")):
                break
            if t in ("turns", "becomes", "gets") and not after_generate and not (rest and (
                    match_color(rest) is not None or rest[0] in ("darker", "brighter", "lighter"))):
                break
            while rest and rest[0] in ("to", "be", "now", "been", "made", "instead", "changed", "turned", "colored"):
                if rest[0] in ("changed", "turned", "colored") and len(rest) > 1 and rest[1] in ("to", "into"):
                    rest = rest[2:]
                    continue
                rest = rest[1:]
            if t in ("has", "have") and not (toks[k + 1:k + 2] == ["to"]):
                break
            if t == "turns" and rest and verb_info(rest[0]) is None and match_color(rest) is None and rest[0] not in (
                    "darker", "brighter", "lighter", "around", "back"):
                break
            return "edit", ["make"] + toks[:k] + rest
        if t in VERBS or t in AUX:
            break
    # a description of the camera alone
    if "camera" in toks or "view" in toks and toks[0] in ("the", "view"):
        rest, spans = _extract_camera_clauses(toks)
        indefinite = any(toks[i] in ("a", "an") and i + 1 < len(toks) for i in range(len(toks)))
        if spans and not indefinite and not any(
                _parse_np(rest, i) is not None and _parse_np(rest, i).kind in ("category", "unknown")
                for i in range(len(rest))):
            return "camera", toks
    return "generate", toks


# -- camera ------------------------------------------------------------------------------------------------

_ORBIT = {"orbit", "orbits", "orbiting", "orbited", "circle", "circles", "circling", "circled", "rotate", "rotates",
          "rotating", "rotated", "revolve", "revolves", "revolving", "around", "round", "spins", "spin", "spinning",
          "sweeps", "sweep", "sweeping", "arcs", "arc"}
_PAN = {"pan", "pans", "panning", "panned", "turns", "turn", "turning", "swivels", "swivel", "swings", "tracks",
        "track", "tracking", "slides", "slide", "sliding", "trucks", "truck"}
_DOLLY = {"dolly", "dollies", "dollying", "zoom", "zooms", "zooming", "push", "pushes", "pushing", "pull", "pulls",
          "pulling", "approaches", "approach", "approaching", "closer", "nearer", "retreats", "retreat", "backs",
          "recedes", "in", "out", "forward", "forwards", "backward", "backwards", "back", "away", "closes"}
_FIXED = {"static", "fixed", "still", "stationary", "locked", "steady", "motionless", "stays", "stay", "remains",
          "immobile", "stable", "unmoving", "tripod", "freeze", "frozen", "stopped", "stops", "stop"}
_CAM_BOUNDARY = {"while", "as", "whereas", "whilst", ",", "but", "meanwhile"}


def _extract_camera_clauses(toks: list[str]) -> tuple[list[str], list[list[str]]]:
    """Split camera clauses ("while the camera circles the table", "with a static camera") from the rest."""
    spans: list[tuple[int, int]] = []
    n = len(toks)
    for i, w in enumerate(toks):
        if w not in ("camera", "cam") and not (w == "view" and i > 0 and toks[i - 1] in ("the", "a")):
            continue
        if i >= 1 and toks[i - 1] in ("the",) and i >= 2 and toks[i - 2] in ("toward", "to", "at", "from", "past",
                                                                            "of", "into", "by"):
            continue
        if i >= 1 and toks[i - 1] in ("toward", "to", "at", "from", "into"):
            continue
        if spans and spans[-1][0] <= i < spans[-1][1]:
            continue
        s = i
        while s > 0 and toks[s - 1] not in _CAM_BOUNDARY and toks[s - 1] != "and" and not (
                verb_info(toks[s - 1]) and toks[s - 1] not in _FIXED and toks[s - 1] not in _ORBIT | _PAN | _DOLLY):
            if toks[s - 1] == "with":
                s -= 1
                break
            s -= 1
        if s > 0 and toks[s - 1] in _CAM_BOUNDARY | {"and"}:
            s -= 1
        e = i + 1
        while e < n and toks[e] not in _CAM_BOUNDARY and toks[e] not in _SEG_PUNCT:
            if toks[e] == "and" and e + 1 < n:
                nxt = _parse_np(toks, e + 1)
                if nxt is not None and nxt.kind in ("category", "unknown") and _clause_boundary(toks, e):
                    break
            e += 1
        spans.append((s, e))
    if not spans:
        return toks, []
    rest: list[str] = []
    cams: list[list[str]] = []
    last = 0
    for s, e in spans:
        rest.extend(toks[last:s])
        cams.append(toks[s:e])
        last = e
    rest.extend(toks[last:])
    while rest and rest[-1] in ("and", ",", "while", "as", "with"):
        rest.pop()
    return rest, cams


def _read_camera(toks: Sequence[str]) -> dict:
    """Camera motion, direction, speed and target from a camera clause."""
    out: dict = {"motion": "fixed"}
    words = list(toks)
    motion = None
    direction = None
    target_np = None
    settings: list[str] = []
    i = 0
    n = len(words)
    while i < n:
        w = words[i]
        sp = _match_phrase(words, i, SPEED_PHRASES)
        if sp is not None:
            out["speed"], out["speed_word"] = sp[0], " ".join(words[i:i + sp[1]])
            i += sp[1]
            continue
        if w in CLOCKWISE_WORDS:
            direction = "clockwise" if CLOCKWISE_WORDS[w] else "counterclockwise"
            motion = motion or "orbit"
            i += 1
            continue
        if w in _ORBIT and w not in ("turns", "turn"):
            motion = "orbit"
            j = i + 1
            while j < n and words[j] in ("around", "round", "about", "slowly", "quickly", "all", "the", "way"):
                if words[j] in ("the", "all", "way"):
                    break
                j += 1
            np_ = _parse_np(words, j) if j < n else None
            if np_ is not None and np_.kind in ("category", "unknown", "setting", "pronoun"):
                target_np = np_
                i = np_.end
                continue
            if np_ is not None:
                if np_.kind == "setting":
                    settings.append(np_.category)
                i = np_.end
                continue
            i += 1
            continue
        if w in _PAN and motion != "orbit":
            motion = "pan"
            i += 1
            continue
        if w in ("zoom", "zooms", "zooming", "dolly", "dollies", "dollying", "push", "pushes", "pushing", "pull",
                 "pulls", "pulling", "closer", "nearer", "approaches", "approach", "approaching", "retreats",
                 "backs", "recedes") and motion != "orbit":
            motion = "dolly"
            if w in ("closer", "nearer", "approaches", "approach", "approaching"):
                direction = "in"
            elif w in ("retreats", "backs", "recedes"):
                direction = "out"
            i += 1
            continue
        if w in ("in", "forward", "forwards", "closer") and motion == "dolly":
            direction = "in"
            i += 1
            continue
        if w in ("out", "back", "backward", "backwards", "away") and motion == "dolly":
            direction = "out"
            i += 1
            continue
        if w in ("left", "right", "leftward", "rightward", "leftwards", "rightwards"):
            if motion in (None, "pan", "fixed"):
                motion = "pan"
                direction = "left" if w.startswith("left") else "right"
            i += 1
            continue
        if w in ("moves", "move", "moving", "goes", "go") and i + 1 < n and words[i + 1] in ("closer", "nearer", "in",
                                                                                              "forward", "toward"):
            motion, direction = "dolly", "in"
            i += 2
            continue
        if w in ("moves", "move", "moving", "goes", "go") and i + 1 < n and words[i + 1] in ("away", "back", "out",
                                                                                              "backward", "backwards"):
            motion, direction = "dolly", "out"
            i += 2
            continue
        if w in _FIXED and motion is None:
            motion = "fixed"
            i += 1
            continue
        if w in ("not", "never") and i + 1 < n and words[i + 1] in ("move", "moves", "moving"):
            motion = "fixed"
            i += 2
            continue
        if w in ("on", "in", "across", "over", "above", "at", "inside") and i + 1 < n:
            np_ = _parse_np(words, i + 1)
            if np_ is not None and (np_.kind == "setting" or np_.head == "table"):
                settings.extend(np_.settings)
                settings.append(np_.category if np_.kind == "setting" else "table")
                i = np_.end
                continue
        s = word_to_setting(w)
        if s is not None and noun_to_category(w) is None:
            settings.append(s)
        i += 1
    out["motion"] = motion or "fixed"
    if out["motion"] == "fixed":
        direction = None
        target_np = None
        out.pop("speed", None)
        out.pop("speed_word", None)
    if out["motion"] == "pan" and direction not in ("left", "right", None):
        direction = None
    out["direction"] = direction
    out["target_np"] = target_np
    out["settings"] = settings
    return out


def _camera_decl_to_edit(toks: list[str]) -> list[str]:
    return ["__camera__"] + toks


# -- edit reading -------------------------------------------------------------------------------------------

_ADDITIVE = {"redder": "red", "bluer": "blue", "greener": "green", "yellower": "yellow", "pinker": "pink",
             "whiter": "white", "oranger": "orange", "purpler": "purple", "greyer": "grey", "grayer": "gray",
             "blacker": "black", "browner": "brown"}
_DARKER = {"darker": 0.6, "dimmer": 0.6, "duller": 0.7, "darken": 0.6, "dim": 0.6, "blacker": 0.6}
_BRIGHTER = {"brighter": 1.5, "lighter": 1.5, "brighten": 1.5, "lighten": 1.5, "shinier": 1.3}
_REMOVE_WORDS = {"disappear", "vanish", "invisible", "gone", "go away", "hidden"}
_LEFTOVER_OK = {"from", "the", "scene", "view", "frame", "picture", "video", "image", "please", "entirely",
                "completely", "now", "too", "as", "well", "also", "again", "out", "away", "of", "in", "world",
                "whole", "entire", "right", "immediately", "instantly", ",", "direction", "motion", "movement",
                "'s", "trajectory", "path", "course", "heading", "velocity", "only", "just"}
_FILLER = {"please", "color", "colored", "coloured", "instead", "again", "too", "now", "one", "ones", "as", "well",
           "in", "the", "scene", "from", "entirely", "completely", "totally", "fully", "of", "tint", "shade",
           "hue", "paint", "also"}


class _EditReader:
    """Reads one edit segment into op drafts (dicts of EditOp fields, targets unresolved)."""

    def __init__(self, toks: list[str]) -> None:
        self.toks = toks
        self.seg = _detok(toks)

    def fail(self, why: str) -> CommandError:
        return CommandError(f"Could not understand the edit {self.seg!r}: {why}. Supported edits: recolour "
                            f"('make the bus yellow', 'make it redder', 'make it darker'), remove ('delete the ball'), "
                            f"extract ('extract the boat'), reverse ('reverse its motion'), redirect ('move the ball to "
                            f"the left'), speed ('make the car twice as fast'), stop ('stop the dog'), camera "
                            f"('orbit the camera clockwise', 'pan left', 'zoom in')")

    def read(self) -> list[dict]:
        toks = self.toks
        if toks and toks[0] == "__camera__":
            cam = _read_camera(toks[1:])
            return [self._camera_op(cam)]
        ops: list[dict] = []
        parts = self._split_ops(toks)
        prev: dict | None = None
        for part in parts:
            part = _skip_preamble(part)
            if not part:
                continue
            got = self._read_one(part, prev)
            ops.extend(got)
            prev = got[-1] if got else prev
        if not ops:
            raise self.fail("no edit found")
        return ops

    def _split_ops(self, toks: list[str]) -> list[list[str]]:
        """Split "make the cube blue and reverse its motion" at "and"/"," before an edit verb."""
        parts: list[list[str]] = []
        cur: list[str] = []
        i = 0
        while i < len(toks):
            w = toks[i]
            if w in ("and", ",", "but") and cur:
                j = i + 1
                while j < len(toks) and toks[j] in ("and", ",", "also", "then", "please"):
                    j += 1
                if j < len(toks) and toks[j] in EDIT_VERBS and toks[j] not in ("show",):
                    # "make it stop and ..." keeps going; "... and delete the car" starts a new op
                    if not (cur[0] in ("make", "let", "have") and toks[j] in ("move", "go", "stop", "bounce", "run",
                                                                              "fly", "drive", "swim", "roll")
                            and self._make_has_no_complement(cur)):
                        parts.append(cur)
                        cur = []
                        i = j
                        continue
                # gapping: "make the ball blue and the cube red"
                if cur and cur[0] in ("make", "turn", "paint", "color", "colour", "dye") and j < len(toks) and \
                        toks[j] in DETS | {"it"} and any(match_color(cur, k) is not None for k in range(2, len(cur))):
                    np_ = _parse_np(toks, j, edit=True)
                    if np_ is not None and np_.end < len(toks) and (match_color(toks, np_.end) is not None
                                                                    or toks[np_.end] in _ADDITIVE):
                        parts.append(cur)
                        cur = [cur[0]]
                        i = j
                        continue
            cur.append(w)
            i += 1
        if cur:
            parts.append(cur)
        return parts

    @staticmethod
    def _make_has_no_complement(cur: list[str]) -> bool:
        np_ = _parse_np(cur, 1, edit=True)
        return np_ is not None and np_.end >= len(cur)

    # one operation ------------------------------------------------------------------------------------------
    def _read_one(self, toks: list[str], prev: dict | None) -> list[dict]:
        w = toks[0]
        rest = toks[1:]
        if w == "__camera__":
            return [self._camera_op(_read_camera(rest))]
        if w in ("make", "let", "have", "turn", "get"):
            if w == "turn" and rest and rest[0] in ("the", "camera") and "camera" in rest[:2]:
                return [self._camera_op(_read_camera(toks))]
            return self._make(rest, verb=w)
        if w in ("paint", "color", "colour", "recolor", "recolour", "dye", "colorize", "recolorize", "shade"):
            targets, k = self._targets(rest)
            tail = [x for x in rest[k:] if x not in ("to", "into", "in", "with", "a", "an")]
            return [self._recolor(targets, tail, assign=True)]
        if w == "tint":
            targets, k = self._targets(rest)
            tail = [x for x in rest[k:] if x not in ("to", "into", "in", "with", "a", "an", "slightly", "bit")]
            col = match_color(tail)
            if col is None:
                raise self.fail("expected a colour to tint with")
            return [self._additive(targets, col, 0.3)]
        if w in ("change", "set", "switch", "alter", "apply"):
            return self._change(rest)
        if w == "give":
            targets, k = self._targets(rest)
            tail = rest[k:]
            col = None
            for j in range(len(tail)):
                col = match_color(tail, j)
                if col is not None:
                    break
            if col is not None and any(x in ("tint", "hue", "shade", "touch") for x in tail):
                return [self._additive(targets, col, 0.3)]
            if col is not None:
                return [self._recolor(targets, [col[0]], assign=True)]
            raise self.fail("expected 'give X a <colour> tint'")
        if w == "add":
            tail = rest
            amount = 0.3
            j = 0
            while j < len(tail) and tail[j] in ("some", "a", "bit", "of", "little", "more", "touch", "hint", "lot",
                                                "alot", "much"):
                if tail[j] in ("bit", "little", "touch", "hint"):
                    amount = 0.15
                if tail[j] in ("lot", "alot", "much"):
                    amount = 0.5
                j += 1
            col = match_color(tail, j)
            if col is None:
                raise self.fail("adding objects is not supported in an edit (describe them when generating); "
                                "'add some blue to X' adds colour")
            k = j + col[2]
            while k < len(tail) and tail[k] in ("to", "onto", "on", "color", "tint"):
                k += 1
            targets, _ = self._targets(tail[k:])
            return [self._additive(targets, col, amount)]
        if w in ("darken", "dim", "blacken"):
            targets, k = self._targets(rest)
            return [self._multiply(targets, _DARKER.get(w, 0.6) * self._amount_mult(rest[k:]))]
        if w in ("brighten", "lighten", "whiten"):
            targets, k = self._targets(rest)
            return [self._multiply(targets, _BRIGHTER.get(w, 1.5))]
        if w == "redden":
            targets, _ = self._targets(rest)
            return [self._additive(targets, ("red", color_rgb("red"), 1), 0.3)]
        if w in ("delete", "remove", "erase", "eliminate", "discard", "getridof", "hide", "clear", "drop", "wipe"):
            if rest and rest[0] in ("out",):
                rest = rest[1:]
            targets, k = self._targets(rest)
            self._no_leftover(rest[k:])
            return [dict(op="remove", targets=targets)]
        if w == "take" and rest and (rest[0] in ("out", "away") or rest[-1] in ("out", "away")):
            r = rest[1:] if rest[0] in ("out", "away") else rest[:-1]
            targets, k = self._targets(r)
            self._no_leftover(r[k:])
            return [dict(op="remove", targets=targets)]
        if w in ("extract", "isolate", "segment", "separate", "single", "pull", "cut", "keep", "show", "only"):
            r = [x for x in rest if x not in ("out", "only", "just")]
            if w in ("keep", "show") and not (rest and rest[0] in ("only", "just")) and not (
                    len(rest) > 1 and rest[-1] in ("only",)):
                if w == "keep" and rest:
                    # "keep the ball moving" / "keep the camera still"
                    return self._make(rest, verb="keep")
                raise self.fail(f"expected '{w} only X'")
            targets, k = self._targets(r)
            self._no_leftover(r[k:])
            return [dict(op="extract", targets=targets)]
        if w in ("reverse", "invert", "flip"):
            r = [x for x in rest if x not in ("the", "direction", "directions", "motion", "movement", "of", "trajectory",
                                              "path", "course", "heading", "velocity", "'s")]
            if not r and rest:
                r = rest
            targets, k = self._targets(r or ["it"])
            self._no_leftover((r or ["it"])[k:])
            return [dict(op="reverse", targets=targets)]
        if w in ("stop", "halt", "freeze", "pause"):
            r = [x for x in rest if x not in ("from", "moving", "motion", "the", "movement", "of")]
            if not r:
                r = ["it"]
            if "camera" in rest:
                return [self._camera_op({"motion": "fixed"})]
            targets, _ = self._targets(rest if rest and rest[0] in DETS | PRONOUNS | {"all", "everything"} else r)
            return [dict(op="stop", targets=targets)]
        if w in ("speed", "slow", "accelerate", "decelerate", "double", "halve", "triple", "quadruple", "increase",
                 "decrease", "reduce"):
            return [self._speed_verb(w, rest)]
        if w in ("orbit", "circle", "rotate", "pan", "zoom", "dolly"):
            if w in ("orbit", "circle", "rotate") and rest and "camera" not in rest and not any(
                    x in ("view", "viewpoint", "shot") for x in rest):
                # "circle the ball around the tree": a path change
                targets, k = self._targets(rest)
                return self._motion_ops(targets, ["circle"] + rest[k:], implied="circle")
            return [self._camera_op(_read_camera(toks))]
        if w in ("move", "send", "steer", "direct", "guide", "redirect", "bounce", "zigzag", "go", "drive", "fly",
                 "roll", "run", "swim", "sail", "head"):
            if rest and "camera" in rest[:3]:
                return [self._camera_op(_read_camera(toks))]
            if w in ("go", "head", "drive", "fly", "run", "swim", "sail", "roll") and (not rest or rest[0] not in
                                                                                       DETS | PRONOUNS):
                raise self.fail(f"'{w}' needs an object: say which object should {w}")
            targets, k = self._targets(rest)
            implied = {"bounce": "bounce", "zigzag": "zigzag"}.get(w)
            return self._motion_ops(targets, rest[k:], implied=implied, verb=w)
        raise self.fail(f"'{w}' is not an edit this parser knows")

    def _no_leftover(self, rest: Sequence[str]) -> None:
        """Words after the targets of remove/extract/reverse must be fillers ("from the scene"), so that
        "delete everything except the ball" fails instead of deleting everything."""
        extra = [w for w in rest if w not in _LEFTOVER_OK]
        if extra:
            raise self.fail(f"could not read {' '.join(rest)!r} after what to edit")

    # targets -------------------------------------------------------------------------------------------------
    def _targets(self, toks: list[str], required: bool = True) -> tuple[list[_TargetDraft], int]:
        """Parse "the fish and seaweed", "it", "all the balls", "everything", "the camera"."""
        out: list[_TargetDraft] = []
        i = 0
        n = len(toks)
        while i < n:
            w = toks[i]
            if w in ("and", ",", "both", "also") and out or w in ("both",):
                i += 1
                continue
            if w in ("everything", "everybody", "everyone") or (w == "all" and (i + 1 >= n or toks[i + 1] in (
                    "objects", "things", "the", "of", "items", "and", ","))) and not (
                    i + 2 < n and toks[i + 1] == "the" and toks[i + 2] not in ("objects", "things", "items", "scene")):
                j = i + 1
                while j < n and toks[j] in ("objects", "things", "the", "of", "items", "them", "in", "scene"):
                    j += 1
                out.append(_TargetDraft(text=" ".join(toks[i:j]), kind="all", noun="*"))
                i = j
                if i < n and toks[i] in ("and", ","):
                    continue
                break
            if w in ("the", "whole", "entire") and i + 1 < n and toks[i + 1] in ("scene", "whole", "entire", "world"):
                j = i + 1
                while j < n and toks[j] in ("whole", "entire", "scene", "world"):
                    j += 1
                out.append(_TargetDraft(text=" ".join(toks[i:j]), kind="all", noun="*"))
                i = j
                break
            if w in ("it", "them", "they", "its", "their", "itself", "this", "that", "these", "those") and (
                    i + 1 >= n or _stop_word(toks[i + 1]) or toks[i + 1] in ("'s", "motion", "movement", "direction",
                                                                            "speed", "color", "path", "one", "ones")
                    or match_color(toks, i + 1) is not None or toks[i + 1] in _ADDITIVE or toks[i + 1] in _DARKER
                    or toks[i + 1] in _BRIGHTER or w in ("it", "them", "they", "its", "their", "itself")):
                j = i + 1
                if j < n and toks[j] in ("one", "ones"):
                    j += 1
                out.append(_TargetDraft(text=w, kind="pronoun", noun=w, plural=w in ("them", "they", "their")))
                i = j
                if i < n and toks[i] == "'s":
                    i += 1
                break_ok = True
                if i < n and toks[i] in ("and", ",") and i + 1 < n and (toks[i + 1] in DETS or toks[i + 1] in PRONOUNS):
                    continue
                if break_ok:
                    break
            np_ = _parse_np(toks, i, edit=True)
            if np_ is None:
                break
            if np_.kind == "camera":
                out.append(_TargetDraft(text=np_.text, kind="camera", noun="camera"))
            elif np_.kind == "all" or (np_.kind == "generic" and np_.det in ("all", "every", "each")):
                out.append(_TargetDraft(text=np_.text, kind="all", noun="*"))
            elif np_.kind == "pronoun":
                out.append(_TargetDraft(text=np_.text, kind="pronoun", noun=np_.head, plural=np_.plural))
            elif np_.kind == "viewer":
                break
            else:
                noun = singular(np_.head) if np_.plural or np_.kind == "unknown" else np_.head
                out.append(_TargetDraft(text=np_.text, kind="noun", noun=noun, color=np_.color,
                                        plural=np_.plural))
            i = np_.end
            if i < n and toks[i] == "'s":
                i += 1
                break
            if i < n and toks[i] in ("and", ","):
                j = i + 1
                while j < n and toks[j] in ("and", ","):
                    j += 1
                if j < n and (toks[j] in DETS or toks[j] in PRONOUNS or noun_to_category(toks[j]) is not None
                              or (toks[j] not in EDIT_VERBS and not _stop_word(toks[j])
                                  and match_color(toks, j) is None and toks[j] not in _ADDITIVE)):
                    nxt = _parse_np(toks, j, edit=True)
                    if nxt is not None and nxt.kind not in ("viewer",):
                        i = j
                        continue
            break
        if not out and required:
            raise self.fail("expected what to edit (e.g. 'the ball', 'it', 'everything')")
        return out, i

    # "make ..." -----------------------------------------------------------------------------------------------
    def _make(self, rest: list[str], verb: str = "make") -> list[dict]:
        # "make the color of X C", "make X's color C"
        r = list(rest)
        if r[:3] in (["the", "color", "of"], ["the", "colors", "of"]) or r[:2] == ["color", "of"]:
            k = r.index("of")
            targets, j = self._targets(r[k + 1:])
            tail = r[k + 1 + j:]
            return [self._recolor(targets, tail, assign=True)]
        if r and r[0] == "the" and len(r) > 1 and r[1] == "camera" or r and r[0] == "camera":
            return [self._camera_op(_read_camera(r))]
        targets, j = self._targets(r)
        tail = r[j:]
        if tail and tail[0] in ("color", "colors") and "of" not in tail[:1]:
            tail = tail[1:]
        return self._complement(targets, tail, verb)

    def _complement(self, targets: list[_TargetDraft], tail: list[str], verb: str) -> list[dict]:
        tail = [x for x in tail if x not in ("be", "look", "become", "appear", "seem", "to", "please")] if not (
            tail and tail[0] in ("to", "toward")) else tail
        if not tail:
            raise self.fail("nothing says what to change")
        if any(t.kind == "camera" for t in targets):
            return [self._camera_target_ops(targets, tail)]
        t0 = tail[0]
        if t0 in ("bigger", "smaller", "larger", "taller", "shorter", "wider", "thinner", "huge", "tiny", "big",
                  "small", "large"):
            raise self.fail("resizing objects is not supported")
        if t0 in ("disappear", "vanish", "invisible", "gone", "hidden") or tail[:2] == ["go", "away"]:
            return [dict(op="remove", targets=targets)]
        if t0 in ("stop", "halt", "freeze", "still", "stationary", "static", "motionless", "pause") or tail[:2] in (
                ["stand", "still"], ["stay", "still"], ["not", "move"], ["stay", "put"], ["come", "to"],
                ["keep", "still"], ["stop", "moving"]):
            return [dict(op="stop", targets=targets)]
        if t0 in ("reverse", "backwards", "backward") or tail[-2:] == ["in", "reverse"] or tail[:2] in (["go", "back"], ["turn", "around"],
                                                                       ["move", "backwards"], ["go", "backwards"],
                                                                       ["move", "backward"], ["go", "backward"],
                                                                       ["run", "backwards"]) \
                or ("opposite" in tail and ("way" in tail or "direction" in tail)) or tail[-2:] == ["other", "way"]:
            return [dict(op="reverse", targets=targets)]
        # colour complements
        op = self._colour_complement(targets, tail)
        if op is not None:
            return [op]
        if verb == "turn" and (t0 in ("left", "right", "around") or t0 in DIRECTION_WORDS):
            if t0 == "around":
                return [dict(op="reverse", targets=targets)]
            return self._motion_ops(targets, tail, verb="turn")
        # motion complements: speed, direction, path
        ops = self._motion_ops(targets, tail, verb=verb, allow_fail=True)
        if ops:
            return ops
        col_word = next((x for x in tail if x.isalpha() and not _known_word(x) and x not in _FILLER), None)
        if col_word is not None and len(tail) <= 3:
            raise self.fail(f"unknown colour or change {col_word!r}; colours are the CSS names (e.g. red, navy, "
                            f"lightblue, goldenrod) optionally after light/dark/pale/bright")
        raise self.fail(f"could not read {' '.join(tail)!r}")

    def _colour_complement(self, targets: list[_TargetDraft], tail: list[str]) -> dict | None:
        tail = [x for x in tail if x not in ("a", "an", "some", "into", "in", "colored", "painted", "look")]
        if not tail:
            return None
        amount_mult = self._amount_mult(tail)
        core = [x for x in tail if x not in ("slightly", "bit", "little", "much", "alot", "lot", "far", "way",
                                               "somewhat", "tad", "even", "more", "less", "a", "lot") or x in (
            "more", "less")]
        if not core:
            return None
        # multiplicative
        if core[0] in _DARKER or core[0] in _BRIGHTER:
            f = _DARKER.get(core[0]) or _BRIGHTER[core[0]]
            if core[0] in _DARKER:
                f = {1.0: f, 2.0: 0.4, 0.5: 0.8}[amount_mult]
            else:
                f = {1.0: f, 2.0: 2.0, 0.5: 1.25}[amount_mult]
            return self._multiply(targets, f)
        if core[:3] in (["half", "as", "bright"], ["half", "as", "light"]):
            return self._multiply(targets, 0.5)
        if core[:3] in (["twice", "as", "bright"], ["double", "as", "bright"]):
            return self._multiply(targets, 2.0)
        if len(core) >= 3 and _number_at(core, 0) is not None and core[1] == "times" and core[2] in (
                "brighter", "darker", "as"):
            v = _number_at(core, 0)[0]
            if v <= 0:
                raise self.fail("a brightness factor must be > 0")
            return self._multiply(targets, float(v) if core[2] in ("brighter", "as") else 1.0 / v)
        # additive
        if core[0] in _ADDITIVE:
            name = _ADDITIVE[core[0]]
            return self._additive(targets, (name, color_rgb(name), 1), 0.3 * amount_mult)
        if core[0] in ("more", "less") and len(core) > 1:
            col = match_color(core, 1)
            if col is not None:
                return self._additive(targets, col, (0.3 if core[0] == "more" else -0.3) * amount_mult)
            if core[1] in ("bright", "vivid", "vibrant", "dark", "light"):
                bright = core[1] in ("bright", "vivid", "vibrant", "light")
                up = core[0] == "more"
                return self._multiply(targets, 1.5 if bright == up else 0.6)
        # assign
        col = match_color(core, 0)
        if col is not None:
            rest = [x for x in core[col[2]:] if x not in _FILLER]
            if rest and rest[0] in ("and",):
                rest = []
            if rest:
                if any(x in ("tint", "tinge", "hue") for x in core):
                    return self._additive(targets, col, 0.3 * amount_mult)
                return None
            if any(x in ("tint", "tinge") for x in tail):
                return self._additive(targets, col, 0.3 * amount_mult)
            return self._recolor(targets, [col[0]] if " " not in col[0] else col[0].split(), assign=True)
        if core[0] in COLOR_MODIFIERS or core[0] in MODIFIER_SYNONYMS:
            if len(core) > 1 and core[1].isalpha() and not _known_word(core[1]):
                raise self.fail(f"unknown colour {core[1]!r}; colours are the CSS names (e.g. red, navy, lightblue) "
                                f"optionally after light/dark/pale/bright")
        return None

    @staticmethod
    def _amount_mult(tail: Sequence[str]) -> float:
        if any(x in ("much", "alot", "lot", "far", "way", "considerably") for x in tail):
            return 2.0
        if any(x in ("slightly", "bit", "little", "somewhat", "tad", "touch") for x in tail):
            return 0.5
        return 1.0

    def _recolor(self, targets: list[_TargetDraft], tail: list[str], assign: bool = True) -> dict:
        tail = [x for x in tail if x not in ("to", "into", "in", "a", "an", "the", "color", "colour", "as", "well")]
        col = match_color(tail, 0) if tail else None
        if col is None:
            word = next((x for x in tail if x not in _FILLER), None)
            if word is None:
                raise self.fail("expected a colour (e.g. 'make the bus yellow')")
            op = self._colour_complement(targets, tail)
            if op is not None:
                return op
            raise self.fail(f"unknown colour {' '.join(tail)!r}; colours are the CSS names (e.g. red, navy, lightblue, "
                            f"goldenrod) optionally after light/dark/pale/bright")
        leftover = [x for x in tail[col[2]:] if x not in _FILLER and x not in (",", "and", "please")]
        if leftover:
            raise self.fail(f"could not read {' '.join(tail)!r} as one colour")
        return dict(op="recolor", targets=targets, mode="assign", color=ColorSpec(col[0], col[1]))

    @staticmethod
    def _additive(targets: list[_TargetDraft], col: tuple, amount: float) -> dict:
        amount = max(-1.0, min(1.0, amount))
        delta = tuple(round(amount * c, 6) + 0.0 for c in col[1])
        return dict(op="recolor", targets=targets, mode="additive", color=ColorSpec(col[0], col[1]), delta=delta)

    def _multiply(self, targets: list[_TargetDraft], f: float) -> dict:
        if f <= 0:
            raise self.fail("a brightness factor must be > 0")
        f = round(f, 6)
        return dict(op="recolor", targets=targets, mode="multiplicative", factor_rgb=(f, f, f))

    # change / set -----------------------------------------------------------------------------------------
    def _change(self, rest: list[str]) -> list[dict]:
        r = list(rest)
        if "camera" in r[:3]:
            return [self._camera_op(_read_camera(r))]
        attr = None
        # "the color of X to C" / "X's color to C" / "X to C"
        if r[:1] == ["the"] and len(r) > 2 and r[1] in ("color", "colors", "direction", "speed", "motion", "path",
                                                        "movement", "trajectory", "velocity") and r[2] == "of":
            attr = r[1]
            targets, j = self._targets(r[3:])
            tail = r[3 + j:]
        else:
            targets, j = self._targets(r)
            tail = r[j:]
            if tail and tail[0] in ("color", "colors", "direction", "speed", "motion", "path", "movement",
                                    "trajectory", "velocity"):
                attr = tail[0]
                tail = tail[1:]
        while tail and tail[0] in ("to", "into", "a", "an", "from", "so", "that", "it", "is"):
            if tail[0] == "from":  # "change X from red to blue"
                k = tail.index("to") if "to" in tail else len(tail)
                tail = tail[k:]
                continue
            tail = tail[1:]
        if attr in ("color", "colors") or (attr is None and tail and (match_color(tail) is not None
                                                                      or tail[0] in _ADDITIVE)):
            return [self._recolor(targets, tail, assign=True)]
        if attr in ("direction", "motion", "path", "movement", "trajectory", "velocity"):
            if not tail or tail in (["around"],) or tail[0] in ("opposite", "reverse", "reversed", "backwards"):
                return [dict(op="reverse", targets=targets)]
            return self._motion_ops(targets, tail, verb="change")
        if attr == "speed":
            if not tail:
                raise self.fail("expected a new speed (e.g. 'change the speed of the car to slow')")
            return self._motion_ops(targets, tail, verb="change", speed_only=True)
        return self._complement(targets, tail, "change")

    # speed --------------------------------------------------------------------------------------------------
    def _speed_verb(self, w: str, rest: list[str]) -> dict:
        r = list(rest)
        factor: float | None = None
        if w in ("speed", "slow"):
            if r and r[0] in ("up", "down"):
                r = r[1:]
            elif r and r[-1] in ("up", "down"):
                r = r[:-1]
            factor = 2.0 if w == "speed" else 0.5
        elif w in ("accelerate", "increase"):
            factor = 2.0
        elif w in ("decelerate", "decrease", "reduce"):
            factor = 0.5
        elif w == "double":
            factor = 2.0
        elif w == "halve":
            factor = 0.5
        elif w == "triple":
            factor = 3.0
        elif w == "quadruple":
            factor = 4.0
        r = [x for x in r if x not in ("the", "speed", "of", "'s", "velocity", "pace")] if (
            "speed" in r or "of" in r or "velocity" in r or "pace" in r) else r
        mult = self._amount_mult(r)
        if w in ("speed", "accelerate", "increase") and mult != 1.0:
            factor = {2.0: 3.0, 0.5: 1.25}[mult]
        if w in ("slow", "decelerate", "decrease", "reduce") and mult != 1.0:
            factor = {2.0: round(1 / 3, 6), 0.5: 0.8}[mult]
        r = [x for x in r if x not in ("a", "bit", "little", "lot", "alot", "much", "slightly", "way", "far")]
        by = None
        if "by" in r:
            k = r.index("by")
            by = r[k + 1:]
            r = r[:k]
        if not r:
            r = ["it"]
        targets, j = self._targets(r)
        if by:
            num = _number_at(by, 0)
            if num is not None and len(by) > num[1] and by[num[1]] == "percent":
                p = num[0] / 100.0
                factor = 1 + p if w in ("speed", "accelerate", "increase") else 1 - p
            elif num is not None and len(by) > num[1] and by[num[1]] in ("times",):
                factor = float(num[0]) if w in ("speed", "accelerate", "increase") else (
                    1.0 / num[0] if num[0] else 0.0)
            elif by[:1] == ["half"]:
                factor = 1.5 if w in ("speed", "accelerate", "increase") else 0.5
        if factor is None or factor <= 0:
            raise self.fail("the speed factor must be > 0 (say 'stop' to stop a motion)")
        if targets and targets[0].kind == "camera":
            return dict(op="speed", targets=targets, factor=round(factor, 6))
        return dict(op="speed", targets=targets, factor=round(factor, 6))

    # motion ops ----------------------------------------------------------------------------------------------
    def _motion_ops(self, targets: list[_TargetDraft], tail: list[str], implied: str | None = None,
                    verb: str | None = None, allow_fail: bool = False, speed_only: bool = False) -> list[dict]:
        pred = _Pred()
        scanner = _PhraseScanner(tail, edit=True)
        scanner.scan(0, len(tail), pred)
        if tail and tail[0] in ("to", "at") and pred.speed is None and pred.factor is None and speed_only:
            pass
        if speed_only and pred.speed is None and pred.factor is None:
            num = _number_at(tail, 0)
            if tail[:1] == ["half"]:
                pred.factor = 0.5
            elif tail[:1] in (["double"], ["twice"]):
                pred.factor = 2.0
            elif num is not None:
                if num[0] <= 0:
                    raise self.fail("the speed factor must be > 0 (say 'stop' to stop a motion)")
                pred.factor = float(num[0])
        if implied and not pred.path:
            pred.path = implied
        ops: list[dict] = []
        if pred.reverse and not (pred.dirs or pred.to_side or pred.end):
            return [dict(op="reverse", targets=targets)]
        direction = _combine_directions(pred, tail)
        path = None
        kinds = [k for _, k in pred.verbs]
        if pred.path:
            path = pred.path
        elif pred.clockwise is not None or pred.around is not None:
            path = "circle"
        elif pred.oscillate:
            path = "oscillate"
            direction = direction or pred.oscillate_axis
        else:
            for k in ("zigzag", "circle", "bounce", "oscillate"):
                if k in kinds:
                    path = k
                    break
        if ("stop" in kinds or pred.stationary) and not (direction or path):
            return [dict(op="stop", targets=targets)]
        if pred.negated and ("move" in kinds or not kinds):
            return [dict(op="stop", targets=targets)]
        if direction is not None or path is not None or pred.end is not None or pred.around is not None:
            d: dict = dict(op="redirect", targets=targets, direction_world=direction, path=path,
                           clockwise=pred.clockwise if path == "circle" else None)
            if pred.end is not None:
                d["end_np"] = pred.end
            if pred.around is not None:
                d["around_np"] = pred.around
            ops.append(d)
        if pred.factor is not None:
            ops.append(dict(op="speed", targets=list(targets), factor=pred.factor))
        elif pred.speed is not None:
            ops.append(dict(op="speed", targets=list(targets), speed=pred.speed, speed_word=pred.speed_word))
        if not ops:
            if allow_fail:
                return []
            raise self.fail("expected a direction, path or speed (e.g. 'move the ball to the left')")
        return ops

    # camera --------------------------------------------------------------------------------------------------
    def _camera_op(self, cam: dict) -> dict:
        spec = CameraSpec(motion=cam.get("motion", "fixed"), direction=cam.get("direction"),
                          speed=cam.get("speed", 1.0), speed_word=cam.get("speed_word"))
        d = dict(op="camera", camera=spec)
        if cam.get("target_np") is not None:
            d["camera_target_np"] = cam["target_np"]
        return d

    def _camera_target_ops(self, targets: list[_TargetDraft], tail: list[str]) -> dict:
        cam_t = [t for t in targets if t.kind == "camera"]
        pred = _Pred()
        _PhraseScanner(tail, edit=True).scan(0, len(tail), pred)
        if pred.factor is not None:
            return dict(op="speed", targets=cam_t, factor=pred.factor)
        if pred.reverse:
            return dict(op="reverse", targets=cam_t)
        return self._camera_op(_read_camera(["camera"] + tail))


def parse_rules(text: str, scene: Any = None, require_scene: bool = False) -> Plan:
    """Parse a command with the rule-based parser.

    Args:
        text: the command.
        scene: optional scene (duck-typed: ``.objects`` with ``.name``/``.category``) that edits
            refer to.
        require_scene: raise when an edit has no scene (and no generated plan) to apply to.

    Raises:
        CommandError: the text is empty, not understood, contradictory, or refers to things that
            are not there; the message says what was not understood and what would be.
    """
    if not isinstance(text, str):
        raise CommandError(f"Expected the command as a string, found {type(text).__name__}")
    if not text.strip():
        raise CommandError("Could not understand an empty command. Try e.g. " + ", ".join(EXAMPLES))
    if len(text) > MAX_TEXT_CHARS:
        raise CommandError(f"Could not parse a command of {len(text)} characters: at most {MAX_TEXT_CHARS}")
    return _RuleParser(text, scene, require_scene).parse()
