"""Grounding nouns to the generator's categories, and edit targets to a scene's objects.

Nouns of the rule vocabulary (names, synonyms, plurals in `vocabulary.py`) are grounded by table.
Any other noun is grounded by MiniLM sentence embeddings (`embeddings.py`): the phrase "a <noun>" is
compared with each category's name phrase and description, and the best category wins when

- its cosine similarity is at least `GROUNDING_FLOOR` (`GROUNDING_FLOOR_UNKNOWN_WORD` for a word that
  is not in the tokenizer's English word list), and
- it beats every "reject anchor" (phrases for abstract things, sounds, food, made-up words), which
  keeps made-up or off-library words from landing on an arbitrary category;

otherwise `CommandError` lists the known categories. So "sedan" -> car, "puppy" -> dog.

Before that, an asset the noun names wins ("guitar" -> "Electric guitar"), and with WordNet
installed (`hypernyms.py`) the grounding is checked: a category the noun is a kind of, else a
candidate WordNet relates to it or one at least `CHECKED_FLOOR` similar. What happens to a noun
nothing checked matches is the grounding level (`LEVELS`, one setting; `grounding_level`):

- "exact": like "kind", and then any substitution at all is refused (`parse(grounding="exact")`,
  the old `strict=True`);
- "checked": refused, the `CommandError` listing the nearest candidates;
- "kind" (default): a stand-in of the same kind, the most similar candidate sharing the noun's
  nearest meaningful WordNet hypernym ("kangaroo" -> a mammal, never a duck;
  `hypernyms.GENERIC_KINDS` such as animal, artifact, object do not count), always a
  substitution (warned, recorded in provenance); refused like "checked" when nothing shares a kind;
- "nearest": the nearest category, shape or asset above the floors (the grounding before WordNet).

Without WordNet every level but "exact" grounds as "nearest" (no kinds to check).

Edit targets resolve against a scene's objects (duck-typed: ``.objects`` with ``.name`` and
``.category``; ``.id``, ``.role`` and ``.color`` are used when present) by, in order: everything
("all", "everything"), exact name, category (through the vocabulary), setting name, then embedding
similarity with the objects' names and categories (floor `SCENE_FLOOR`: "the vehicle" -> the bus).
"""

from __future__ import annotations

import os
import re
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..colors import is_color_word
from ..errors import AmbiguousTargetError, CommandError, TargetNotFoundError
from . import embeddings, hypernyms, open_vocab, wordnet
from .open_vocab import is_open_category as is_open
from .lexicon import english_words
from .vocabulary import CATEGORIES, SETTINGS, noun_to_category, singular, word_to_setting

__all__ = ["DEFAULT_LEVEL", "GROUNDING_FLOOR", "LEVELS", "LEVEL_VAR", "SCENE_FLOOR", "Grounding", "ground_noun",
           "ground_noun_vocabulary", "grounding_level", "using_level", "SceneItem", "scene_items", "resolve_in_scene",
           "CAMERA_WORDS", "ALL_WORDS"]

GROUNDING_FLOOR = 0.45
# Words outside the tokenizer's English word list (made-up words, rare compounds) need more: made-up
# words drift towards arbitrary categories at ~0.45-0.50 (calibrated on 76 real and 30 bad nouns).
GROUNDING_FLOOR_UNKNOWN_WORD = 0.52
SCENE_FLOOR = 0.45
# With real assets (an open world), a noun WordNet does not relate to a candidate needs this much:
# "kitten" -> cat (0.77) passes, "tiger" -> elephant (0.53) and "pear" -> apple (0.72) do not.
CHECKED_FLOOR = 0.75
LEVEL_VAR = "MORPHOSIM_GROUNDING"
LEVELS = ("exact", "checked", "kind", "nearest")
DEFAULT_LEVEL = "kind"
# old spellings: $MORPHOSIM_GROUNDING=strict was today's "checked" (deprecated, still read)
LEVEL_ALIASES = {"strict": "checked"}
CHECKED_TOP = 8           # candidates (categories, and shapes and assets) checked against WordNet
KIND_TOP = 100            # open candidates (shapes and assets, most similar first) a stand-in is looked for among
AMBIGUITY_MARGIN = 0.03   # other categories this close to the best match make a target ambiguous
ALL_MARGIN = 0.1          # "all the animals": every category this close to the best match
CAMERA_WORDS = ("camera", "view", "viewpoint", "shot", "cam")
ALL_WORDS = ("*", "everything", "all", "scene", "objects", "things", "everybody", "everyone")

_REJECT_ANCHORS = ("something abstract", "an abstract idea", "a feeling", "a sound", "a made-up word",
                   "random letters", "gibberish", "food", "a place", "weather", "time", "a number", "a colour",
                   "an electronic device")


@dataclass(frozen=True)
class Grounding:
    """Result of grounding a noun: kind is "category", "setting" or "camera"; method is
    "vocabulary", "embedding" or "open" (then `similarity` is the cosine similarity), or "kind" for
    a stand-in of the same kind (`shared_kind` names the WordNet sense both are kinds of)."""

    noun: str
    category: str
    kind: str = "category"
    method: str = "vocabulary"
    similarity: float | None = None
    shared_kind: str | None = None


def ground_noun_vocabulary(noun: str, settings: bool = False) -> Grounding | None:
    """Table lookup only (no model): category synonyms and plurals, then optionally settings."""
    hit = noun_to_category(noun)
    if hit is not None:
        return Grounding(singular(noun) if hit[1] else noun, hit[0])
    if settings:
        if noun in CAMERA_WORDS:
            return Grounding(noun, "camera", kind="camera")
        s = word_to_setting(noun)
        if s is not None:
            return Grounding(noun, s, kind="setting")
    return None


_anchor_lock = threading.Lock()
_anchors: dict[bool, tuple[np.ndarray, list[tuple[str, str]], np.ndarray]] = {}


def _anchor_table(settings: bool) -> tuple[np.ndarray, list[tuple[str, str]], np.ndarray]:
    with _anchor_lock:
        if settings not in _anchors:
            labels: list[tuple[str, str]] = []
            phrases: list[str] = []
            for c in CATEGORIES.values():
                for p in (f"a {c.name}", c.description):
                    labels.append(("category", c.name))
                    phrases.append(p)
            if settings:
                for s, words in SETTINGS.items():
                    labels.append(("setting", s))
                    phrases.append(f"the {words[0]}")
            table = embeddings.encode_table(phrases + list(_REJECT_ANCHORS))
            _anchors[settings] = (table[:len(phrases)], labels, table[len(phrases):])
        return _anchors[settings]


def ground_noun(noun: str, settings: bool = False, floor: float | None = None, phrase: str | None = None) -> Grounding:
    """Ground a noun to a category (or, with ``settings=True``, a setting or the camera).

    Tries the vocabulary, basic shapes and assets named by the noun first; then, as the grounding
    level says (`_ground_by_level`), the checked grounding, a stand-in of the same kind, or the
    nearest category for "a <phrase>" (``phrase`` defaults to the noun; the rule parser passes the
    noun with its descriptive words, e.g. "golden retriever"). Loads the embedding model (once)
    when it gets that far.

    Raises:
        CommandError: nothing the level allows; the message lists the known categories and the
            nearest candidates.
    """
    noun = noun.strip().lower()
    # a compound WordNet knows ("sewing machine") is not shown by any asset of its head ("Coffee machine"),
    # nor by the vocabulary's category of its head when it names another thing ("hot dog" is no dog)
    compound = hypernyms.compound_tail(phrase) if phrase and phrase != noun else None
    hit = ground_noun_vocabulary(noun, settings) or ground_noun_vocabulary(singular(noun), settings)
    if hit is not None and not (compound and hit.kind == "category"
                                and hypernyms.names_other_thing(compound, hit.category)) \
            and not (hit.kind == "category" and hypernyms.synonym_sibling(noun)):
        return hit          # a synonym WordNet calls a sibling kind ("stool" of chair) is grounded as open
    if open_vocab.shape_for_word(noun):                                   # open vocabulary: basic shapes
        return Grounding(noun, open_vocab.shape_for_word(noun))
    mods = () if compound else _noun_modifiers(phrase or noun)
    named = _named_asset(noun, compound or phrase, compound is not None or bool(mods))
    if named is not None:
        return named
    floor = _default_floor(noun) if floor is None else floor
    with _modifiers(mods):
        return _ground_by_level(noun, phrase, settings, floor, kind_noun=compound or noun)


# the noun modifiers of the phrase being grounded (`_noun_modifiers`), for `_shows_modifiers`
_MODS: ContextVar[tuple[str, ...]] = ContextVar("morphosim_grounding_modifiers", default=())


@contextmanager
def _modifiers(mods: tuple[str, ...]) -> Iterator[None]:
    token = _MODS.set(mods)
    try:
        yield
    finally:
        _MODS.reset(token)


def _noun_modifiers(phrase: str) -> tuple[str, ...]:
    """The words before the head of a phrase WordNet does not know whole that are nouns themselves,
    not colours ("stop" of "stop sign", "rice" of "rice cooker"; not "red", nor "wooden"): such a
    phrase names a kind of its head that a sibling kind does not show ("Emergency sign", "Water cooler")."""
    words = phrase.lower().split()[:-1]
    return tuple(w for w in words if w.isalpha() and not is_color_word(w) and wordnet.senses(w, 1))


def _shows_modifiers(text: str) -> bool:
    """Whether a candidate's name can show the phrase being grounded: it holds the phrase's noun
    modifiers, or it is its head alone (a general "Sign" may show a stop sign, "Emergency sign" not)."""
    mods = _MODS.get()
    if not mods:
        return True
    words = open_vocab.name_words(text)
    plain = hypernyms.plain_name(text)                     # "Frame Chambord" is a frame alone
    return set(mods) <= words or len(re.findall(r"[a-z]+", plain.lower().removeprefix("a "))) <= 1


def _ground_by_level(noun: str, phrase: str | None, settings: bool, floor: float, kind_noun: str) -> Grounding:
    """A noun no table or name grounds, at the grounding level in force (see the module doc)."""
    level = grounding_level()
    if level == "nearest" or not wordnet.available():
        return _ground_nearest(noun, phrase, settings, floor)
    checked = _ground_checked(noun, phrase or noun, settings, floor, kind_noun)
    if checked is not None:
        return checked
    stand_in = _ground_kind(noun, phrase or noun, kind_noun) if level in ("kind", "exact") else None
    if stand_in is not None:
        return stand_in
    best = open_vocab.nearest_candidates(phrase or noun, k=1)
    why = ("nothing checked shows it" if level == "checked" else "nothing checked shows it and no candidate is "
           "of the same kind") + (f"; the most similar is {best[0].text!r} at {best[0].similarity:.2f}" if best else "")
    raise _unknown_noun(noun, phrase or noun, settings, why + f"; grounding level {level!r}")


def _named_asset(noun: str, phrase: str | None, compound: bool) -> Grounding | None:
    """The candidate the phrase, else (unless the phrase is a compound) the noun, names."""
    named = (phrase and phrase != noun and open_vocab.ground_named(phrase)) or \
        (None if compound else open_vocab.ground_named(noun))
    return Grounding(noun, named.category, method="open", similarity=named.similarity) if named else None


def _default_floor(noun: str) -> float:
    words = english_words()
    return GROUNDING_FLOOR if (not words or all(w in words for w in noun.split())) else GROUNDING_FLOOR_UNKNOWN_WORD


_level: ContextVar[str | None] = ContextVar("morphosim_grounding_level", default=None)


def grounding_level(value: str | None = None) -> str:
    """The grounding level in force: `value` when given, else the one `using_level` set, else
    `$MORPHOSIM_GROUNDING`, else `DEFAULT_LEVEL` ("kind"). Old spellings (`LEVEL_ALIASES`) are read.

    Raises:
        ValueError: not one of `LEVELS` (the message names where it came from).
    """
    where = "grounding"
    if value is None:
        value = _level.get()
    if value is None:
        value, where = os.environ.get(LEVEL_VAR, "").strip() or DEFAULT_LEVEL, f"${LEVEL_VAR}"
    level = LEVEL_ALIASES.get(str(value).strip().lower(), str(value).strip().lower())
    if level not in LEVELS:
        raise ValueError(f"Expected {where} in {LEVELS}, found {value!r}")
    return level


@contextmanager
def using_level(level: str | None) -> Iterator[str]:
    """Ground with `level` inside the block (None: leave the level in force as it is)."""
    token = _level.set(grounding_level(level)) if level is not None else None
    try:
        yield grounding_level()
    finally:
        if token is not None:
            _level.reset(token)


def _ground_nearest(noun: str, phrase: str | None, settings: bool, floor: float) -> Grounding:
    """The nearest category, or open candidate, above the floors (the grounding without WordNet)."""
    vec, labels, reject = _anchor_table(settings)
    q = embeddings.embed([f"a {phrase or noun}"])[0]
    sims = vec @ q
    best = int(np.argmax(sims))
    score = float(sims[best])
    worst_reject = float(np.max(reject @ q))
    opened = open_vocab.ground_open(phrase or noun, max(open_vocab.OPEN_FLOOR, floor))   # open vocabulary
    if opened is not None and (opened.similarity > score or score < floor or worst_reject > score):
        return Grounding(noun, opened.category, method="open", similarity=round(opened.similarity, 4))
    if score < floor or worst_reject > score:
        raise _unknown_noun(noun, phrase or noun, settings, f"best {labels[best][1]!r} at similarity {score:.2f}, "
                            f"needs {floor:.2f}")
    kind, category = labels[best]
    return Grounding(noun, category, kind=kind, method="embedding", similarity=round(score, 4))


def _unknown_noun(noun: str, phrase: str, settings: bool, why: str) -> CommandError:
    known = ", ".join(CATEGORIES)
    extra = f"; settings: {', '.join(SETTINGS)}" if settings else ""
    return CommandError(f"Could not understand the noun {noun!r}: it is not close to any object category "
                        f"({why}). Known categories: {known}{extra}. Nearest shapes and assets: "
                        + ", ".join(f"{m.text} ({m.similarity:.2f})" for m in open_vocab.nearest_candidates(phrase)))


def _ground_checked(noun: str, phrase: str, settings: bool, floor: float, kind_noun: str) -> Grounding | None:
    """Grounding when real assets make the world open: a category the noun is a kind of (WordNet),
    else the most similar category, shape or asset that WordNet relates to the noun (from `floor`)
    or that is very similar (`CHECKED_FLOOR`); else None, or with the "strict" policy a
    `CommandError` with the nearest candidates. `kind_noun` is what WordNet is asked about (the
    compound "sewing machine" for the noun "machine")."""
    vec, labels, reject = _anchor_table(settings)
    q = embeddings.embed([f"a {phrase}"])[0]
    sims = vec @ q
    kind = hypernyms.kind_category(kind_noun, CATEGORIES)
    if kind is not None:
        sim = max(float(sims[i]) for i, lab in enumerate(labels) if lab == ("category", kind))
        return Grounding(noun, kind, method="embedding", similarity=round(sim, 4))
    pool: dict[tuple[str, str], tuple[float, str]] = {}
    for i in np.argsort(-sims, kind="stable")[:CHECKED_TOP]:
        pool.setdefault(labels[i], (float(sims[i]), labels[i][1]))
    for m in open_vocab.nearest_candidates(phrase, k=CHECKED_TOP):
        pool.setdefault(("open", m.category), (m.similarity, m.text))
    tags = open_vocab.candidate_tags()
    for (kind_, label), (sim, text) in sorted(pool.items(), key=lambda kv: -kv[1][0]):
        if sim < floor:
            break
        if kind_ == "open" and not _shows_modifiers(text):
            continue      # "Water cooler" does not show a rice cooker: at most a stand-in
        if kind_ != "setting" and hypernyms.contradicts(kind_noun, text=None if kind_ == "category" else text,
                                                        category=label if kind_ == "category" else None,
                                                        tags=tags.get(label, ())):
            continue      # a sibling kind ("stool" -> chair) or another sense ("light bulb" -> the lamp): a stand-in at most
        if kind_ == "open" and hypernyms.related(kind_noun, text, tags=tags.get(label, ())) is False:
            continue      # an asset WordNet knows shows the noun only as its thing or a kind of it, never by similarity
        if sim >= CHECKED_FLOOR or (kind_ != "setting" and hypernyms.related(kind_noun, text, tags=tags.get(label, ()))):
            method = "open" if kind_ == "open" else "embedding"
            return Grounding(noun, label, kind="category" if kind_ == "open" else kind_, method=method,
                             similarity=round(sim, 4))
    return None


def _ground_kind(noun: str, phrase: str, kind_noun: str) -> Grounding | None:
    """A stand-in of the same kind: among the categories and the `KIND_TOP` most similar open
    candidates, those sharing the noun's nearest meaningful WordNet hypernym
    (`hypernyms.shared_kind`), the most similar, for the noun's dominant sense that any candidate
    shares; None when none shares one. A candidate at distance 0 (the noun's own sense, or a kind
    of it) is a checked match, not a stand-in."""
    vec, labels, _ = _anchor_table(False)
    q = embeddings.embed([f"a {phrase}"])[0]
    sims = vec @ q
    cands = [(c, max(float(sims[i]) for i, lab in enumerate(labels) if lab == ("category", c)), None, c)
             for c in CATEGORIES]
    cands += [(m.category, m.similarity, m.text, None) for m in open_vocab.nearest_candidates(phrase, k=KIND_TOP)]
    text_of = {label: text for label, _, text, _ in cands}
    tags = open_vocab.candidate_tags()
    for sense in range(hypernyms.noun_sense_count(kind_noun)):   # the dominant sense any candidate shares
        kinds = [(d, -sim, label, name) for label, sim, text, cat in cands
                 for hit in [hypernyms.shared_kind(kind_noun, text=text, category=cat, sense=sense,
                                                   tags=tags.get(label, ()))]
                 if hit is not None for d, name in [hit]]
        if kinds:
            d, neg_sim, label, name = min(kinds)
            cat = label if label in CATEGORIES else None
            if d == 0 and (cat is not None or _shows_modifiers(text_of[label])):   # the noun's own sense, or a kind of it
                return Grounding(noun, label, kind="category", method="open" if is_open(label) else "embedding",
                                 similarity=round(-neg_sim, 4))
            return Grounding(noun, label, method="kind", similarity=round(-neg_sim, 4), shared_kind=name)
    return None


# -- scene resolution --------------------------------------------------------------------------------


@dataclass(frozen=True)
class SceneItem:
    """What target resolution needs of one scene (or plan) object."""

    name: str
    category: str
    id: int
    background: bool = False
    color: tuple[float, float, float] | None = None


def scene_items(scene: Any) -> list[SceneItem]:
    """Read the duck-typed objects of a scene.

    Raises:
        CommandError: `scene` has no usable ``.objects``.
    """
    objs = getattr(scene, "objects", None)
    if objs is None:
        raise CommandError(f"Expected a scene with .objects (each with .name and .category), found "
                           f"{type(scene).__name__}")
    items = []
    for i, o in enumerate(objs):
        name, cat = getattr(o, "name", None), getattr(o, "category", None)
        if not isinstance(name, str) or not isinstance(cat, str):
            raise CommandError(f"Expected scene objects with string .name and .category, found {o!r}")
        oid = getattr(o, "id", i)
        oid = oid if isinstance(oid, (int, np.integer)) and not isinstance(oid, bool) else i
        color = getattr(o, "color", None)
        try:
            color = None if color is None else tuple(float(c) for c in color)[:3]
        except (TypeError, ValueError):
            color = None
        items.append(SceneItem(name, cat, int(oid), getattr(o, "role", "object") == "background", color))
    return items


def _describe(items: Sequence[SceneItem]) -> str:
    return ", ".join(f"{it.name} ({it.category})" if it.name != it.category else it.name for it in items) or "none"


def _numbered_base(name: str) -> str | None:
    """'ball' for the generator's numbered duplicate names ('ball_2'), None for other names."""
    m = re.fullmatch(r"(.+)_\d+", name)
    return m.group(1) if m else None


def resolve_in_scene(noun: str, items: Sequence[SceneItem], text: str | None = None,
                     color: tuple[float, float, float] | None = None) -> list[SceneItem]:
    """The scene objects a target noun refers to.

    Args:
        noun: singular noun ("ball", "vehicle"), "*" for everything.
        items: the scene's objects.
        text: the target as written, for the error message.
        color: RGB of a colour qualifier ("the red ball"): among several matches, keep those whose
            colour is nearest.

    Raises:
        CommandError: nothing matches; the message lists the scene's objects.
    """
    text = text or noun
    if noun in ALL_WORDS:
        hits = [it for it in items if not it.background] or list(items)
        if not hits:
            raise CommandError(f"The scene has no objects to edit for {text!r}")
        return hits
    hits = _by_name(noun, items, color) or _by_vocabulary(noun, items, text) or _by_meaning(noun, items, text)
    if not hits:
        raise TargetNotFoundError(f"Could not find {text!r} in the scene; its objects are: {_describe(items)}")
    if color is not None and len(hits) > 1:
        hits = _nearest_colour(hits, color)
    return hits


def _by_name(noun: str, items: Sequence[SceneItem], color: tuple[float, float, float] | None) -> list[SceneItem]:
    """Objects named by the noun ("ball", "balls"); with a colour, also its numbered siblings ("ball_2")."""
    sing = singular(noun)
    hits = [it for it in items if it.name.lower() in (noun, sing) or singular(it.name.lower()) == sing]
    if color is not None and hits:
        # "the blue ball" among "ball" and "ball_2": numbered siblings share the noun, the colour picks
        hits += [it for it in items if it not in hits and _numbered_base(it.name.lower()) in (noun, sing)]
    return hits


def _by_vocabulary(noun: str, items: Sequence[SceneItem], text: str) -> list[SceneItem]:
    """Objects of the noun's vocabulary category ("the automobile" -> the car).

    Raises:
        TargetNotFoundError: a known category the scene does not have (never re-mapped by meaning).
    """
    sing = singular(noun)
    g = ground_noun_vocabulary(noun, settings=True) or ground_noun_vocabulary(sing, settings=True)
    if g is None:
        return []
    hits = [it for it in items if it.category == g.category]
    if not hits and g.kind == "category":  # "the automobile" -> an object named "car"
        hits = [it for it in items if singular(it.name.lower()) == g.category]
    if not hits and g.kind == "category":
        raise TargetNotFoundError(f"Could not find {text!r} in the scene; its objects are: {_describe(items)}")
    return hits


def _by_meaning(noun: str, items: Sequence[SceneItem], text: str) -> list[SceneItem]:
    """Foreground objects whose name or category is nearest the noun by meaning (backgrounds are
    named by their setting words).

    Raises:
        AmbiguousTargetError: near matches of several categories and no "all".
    """
    pool = [it for it in items if not it.background]
    if not pool or not embeddings.is_available():
        return []
    q = embeddings.embed([f"a {noun}"])[0]
    names = embeddings.embed([f"a {it.name}" for it in pool])
    cats = embeddings.embed([f"a {it.category}" for it in pool])
    score = np.maximum(names @ q, cats @ q)
    best = float(score.max())
    if best < SCENE_FLOOR:
        return []
    wants_all = bool(set(text.lower().split()) & {"all", "every", "both", "each"})
    margin = ALL_MARGIN if wants_all else AMBIGUITY_MARGIN
    close = [it for it, s in zip(pool, score) if s >= max(best - margin, SCENE_FLOOR)]
    categories = sorted({t.category for t in close})
    if len(categories) > 1 and not wants_all:
        raise AmbiguousTargetError(
            f"{text!r} could mean {' or '.join(categories)} (similar matches); name one, or say 'all' to edit "
            f"every match. The scene's objects are: {_describe(items)}")
    return [it for it in pool if it.category in categories]


def _nearest_colour(hits: list[SceneItem], color: tuple[float, float, float]) -> list[SceneItem]:
    """Among several matches, those whose colour is nearest `color` (all of them when none has one)."""
    colored = [it for it in hits if it.color is not None]
    if not colored:
        return hits
    d = [sum((a - b) ** 2 for a, b in zip(it.color, color)) for it in colored]
    m = min(d)
    return [it for it, di in zip(colored, d) if di <= m + 1e-9]
