"""Which category or candidate a noun is a kind of, by WordNet hypernyms (`wordnet.py`).

Embedding similarity alone puts "tiger" next to "elephant" and "pear" next to "apple"; WordNet
says an eagle is a bird and a tiger is not a cat. Only senses of visible things count (animal,
artifact, food, object, plant, person); a person sense counts only when the word has no other
visible sense ("monitor" is a screen, not a proctor). A word's senses are ranked
(`ranked_senses`): most often tagged in WordNet's corpus first, and senses tagged equally often
(most are never tagged) by how near the embedding model puts "a <word>" to each sense's gloss,
so "turtle" is the reptile, not the turtleneck WordNet lists first. A noun is read through its
first ranked senses; a candidate's name through its dominant sense only ("Peacock" is the bird,
not the peacock butterfly). Every function answers None when WordNet is not installed or does
not know the word.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from functools import lru_cache

from . import embeddings, wordnet
from .vocabulary import CATEGORIES, singular

__all__ = ["GENERIC_KINDS", "MAX_ASSET_DEPTH", "MIN_SENSE_SHARE", "compound_tail", "contradicts", "head_word",
           "kind_category", "linked", "names_other_thing", "noun_sense_count", "plain_name", "ranked_senses", "related",
           "shared_kind", "synonym_sibling", "visible_senses", "weighted_senses"]

SENSES = 3                 # a word's most frequent senses that count
MAX_ASSET_DEPTH = 1        # a noun is shown by an asset named by its direct hypernym ("sedan" -> "Car")...
MAX_HYPONYMS = 12          # ... unless that names a broad class: "Tool" (dozens of kinds) does not show a rake
PERSON_CATEGORIES = ("person", "snowboarder")
_CUT = re.compile(r"\s+(?:with|of|for|on|in|and|from)\s+|[(,\-:]")


def plain_name(text: str) -> str:
    """A name without the proper names trailing its head ("Frame Chambord", "Frame Hôi An" -> "Frame"):
    of the capitalised words that end it (never the first word), those from the first that WordNet
    does not know as a noun or that holds letters outside a-z ("Chair Ikea" -> "Chair", "Coffee
    Maker" stays). The name itself when nothing trails, or without WordNet."""
    words = text.split()
    if not wordnet.available():
        return text
    start = len(words)
    while start > 1 and words[start - 1][:1].isupper():
        start -= 1                                 # the capitalised words that end the name...
    cut = next((i for i in range(start, len(words)) if not re.fullmatch(r"[A-Za-z]+", words[i])
                or not wordnet.senses(words[i].lower(), 1)), len(words))
    return " ".join(words[:cut])                   # ... from the first that is no English noun


def head_word(text: str) -> str:
    """The head noun of a name: the last word before any "with"/"of"... clause ("Bowl with fruits"
    -> "bowl") and the proper names after it (`plain_name`), lower case, digits dropped, crudely singular."""
    first = _CUT.split(plain_name(text).lower(), maxsplit=1)[0]
    words = re.findall(r"[a-z]+", first)
    return singular(words[-1]) if words else ""


@lru_cache(maxsize=4096)
def visible_senses(word: str, person: bool = True) -> tuple[wordnet.Synset, ...]:
    """The word's senses that are visible things (see the module doc); `person=False` drops person senses."""
    found = [s for s in wordnet.senses(word, SENSES) if s.lexfile in wordnet.PHYSICAL_LEXFILES]
    if not person or any(s.lexfile != "person" for s in found):
        found = [s for s in found if s.lexfile != "person"]
    return tuple(found)


@lru_cache(maxsize=8192)
def ranked_senses(word: str, person: bool = True) -> tuple[wordnet.Synset, ...]:
    """All the word's visible senses (person senses as in `visible_senses`), the dominant first:
    by how often each was tagged (`wordnet.sense_counts`), ties by the embedding similarity of
    "a <word>" with "<lemma>: <gloss>" (WordNet's order without the model)."""
    found = wordnet.senses(word)
    counts = wordnet.sense_counts(word)
    ranked = [(counts[i] if i < len(counts) else 0, i, s) for i, s in enumerate(found)
              if s.lexfile in wordnet.PHYSICAL_LEXFILES]
    if not person or any(s.lexfile != "person" for _, _, s in ranked):
        ranked = [r for r in ranked if r[2].lexfile != "person"]
    top = max((c for c, _, _ in ranked), default=0)
    tied = [(i, s) for c, i, s in ranked if c == top]
    near = _gloss_nearness(word, tied)
    # the plant a fruit or vegetable grows on is named after it: "a peach" is the fruit, not the tree
    fruit = any(s.lexfile == "food" for _, s in tied)
    ranked.sort(key=lambda r: (-r[0], fruit and r[0] == top and r[2].lexfile == "plant", -near.get(r[1], 0.0), r[1]))
    return tuple(s for _, _, s in ranked)


# a sense tagged less than this share of the word's most tagged visible sense does not count for it:
# "tractor" (tagged 3 : 0) is the farm tractor, not a truck's tractor unit; "rock" (the stone) is no candy
MIN_SENSE_SHARE = 0.5


@lru_cache(maxsize=8192)
def weighted_senses(word: str, person: bool = True) -> tuple[wordnet.Synset, ...]:
    """`ranked_senses` without the senses WordNet's corpus tags far less often than the dominant one
    (under `MIN_SENSE_SHARE` of its count; all of them when none was tagged)."""
    ranked = ranked_senses(word, person)
    found = wordnet.senses(word)
    counts = dict(zip((x.offset for x in found), wordnet.sense_counts(word)))
    top = max((counts.get(x.offset, 0) for x in ranked), default=0)
    return tuple(x for x in ranked if counts.get(x.offset, 0) >= MIN_SENSE_SHARE * top)


def _gloss_nearness(word: str, tied: list[tuple[int, wordnet.Synset]]) -> dict[int, float]:
    """Sense number -> embedding similarity of "a <word>" with "<lemma>: <gloss>", for senses tied
    in count ({} for fewer than two, or without the model)."""
    if len(tied) < 2 or not embeddings.is_available():
        return {}
    vecs = embeddings.embed([f"a {word}"] + [f"{s.lemmas[0].replace('_', ' ')}: {s.gloss.split(';')[0]}"
                                             for _, s in tied])
    return {i: float(v @ vecs[0]) for (i, _), v in zip(tied, vecs[1:])}


@lru_cache(maxsize=256)
def _category_senses(category: str) -> frozenset[int]:
    if category == "person":                            # person.n.01 sits at the top of WordNet
        return frozenset(s.offset for s in wordnet.senses(category, 1))
    declared = CATEGORIES[category].sense if category in CATEGORIES else 0
    if declared:                                        # the sense the generator builds (the lamp is furniture)
        found = wordnet.senses(category, declared)
        return frozenset({found[declared - 1].offset}) if len(found) >= declared else frozenset()
    senses = weighted_senses(category, person=category in PERSON_CATEGORIES)[:SENSES]
    if any(s.lexfile == "animal" for s in senses):      # "bird" the animal, not its meat
        senses = tuple(s for s in senses if s.lexfile != "food")
    return frozenset(s.offset for s in senses)


@lru_cache(maxsize=4096)
def _closure(offset: int) -> dict[int, int]:
    s = wordnet.synset(offset)
    return wordnet.hypernym_closure(s) if s is not None else {}


def _noun_senses(noun: str) -> tuple[wordnet.Synset, ...]:
    """The noun's `SENSES` first weighted senses (its singular's when it has none; `weighted_senses`)."""
    return (weighted_senses(noun) or weighted_senses(singular(noun)))[:SENSES]


def kind_category(noun: str, categories: Iterable[str]) -> str | None:
    """The category the noun's most frequent visible sense is a kind of (nearest one), else None
    ("pear" is the fruit, not the pear tree, so not a kind of tree)."""
    senses = _noun_senses(noun) if wordnet.available() else ()
    if not senses:
        return None
    closure = _closure(senses[0].offset)
    hits = [(min(closure[o] for o in offs if o in closure), c)
            for c, offs in ((c, _category_senses(c)) for c in categories) if offs & closure.keys()]
    return min(hits)[1] if hits else None


def compound_tail(phrase: str) -> str | None:
    """The longest tail of two or more words of `phrase` that WordNet knows as a visible thing
    ("big hot dog" -> "hot dog", "red sewing machine" -> "sewing machine"), else None."""
    words = phrase.lower().split()
    for k in range(min(len(words), 4), 1, -1):
        tail = " ".join(words[-k:])
        if wordnet.is_visible_noun(tail):
            return tail
    return None


def names_other_thing(compound: str, category: str) -> bool:
    """Whether a compound WordNet knows names something that is not a kind of `category` (a
    generator category its head word names): "hot dog" is food, not a dog; "sheep dog" and
    "school bus" are kinds of their heads. False without WordNet."""
    return wordnet.available() and bool(_noun_senses(compound)) and kind_category(compound, [category]) is None


@lru_cache(maxsize=8192)
def _text_senses(text: str, tags: tuple[str, ...] = ()) -> tuple[wordnet.Synset, ...]:
    """A candidate name's dominant sense: of the whole name when WordNet knows it, else of its head;
    a sense of the head that one of the candidate's tags names comes first ("Small lavatory" tagged
    "washbasin" is the washbasin sense of lavatory, not the toilet room)."""
    words = re.findall(r"[a-z]+", text.lower())
    whole = ranked_senses(" ".join(words)) if len(words) > 1 else ()
    if whole:
        return whole[:1]
    head = head_word(text)
    for tag in tags:     # a tag that makes the head a compound WordNet knows: "Frame" tagged "Picture"
        compound = ranked_senses(f"{tag.lower()} {head}") if head and tag.lower() != head else ()
        if compound:
            return compound[:1]
    senses = ranked_senses(head)
    named = {"_".join(t.lower().split()) for t in tags}
    tagged = tuple(x for x in senses if named & set(x.lemmas))[:1]
    if not tagged and named and head:
        # a tag may name a sense that is no visible thing in WordNet: 0 A.D.'s "Dragon" tagged
        # "firedrake" is the mythical dragon, not the flying lizard (its only visible sense)
        tagged = tuple(x for x in wordnet.senses(head) if named & set(x.lemmas))[:1]
    return tagged or senses[:1]


def related(noun: str, text: str, max_depth: int = MAX_ASSET_DEPTH, tags: tuple[str, ...] = ()) -> bool | None:
    """Whether a candidate named `text` shows a `noun`: the same sense, the noun a kind of it at most
    `max_depth` steps up and not a broad class (`MAX_HYPONYMS`), or it a kind of the noun ("seat" ->
    "Armchair").
    None when WordNet is missing or does not know the noun."""
    if not wordnet.available():
        return None
    mine = _noun_senses(noun)
    if not mine:
        return None
    theirs = _text_senses(text, tuple(tags))
    for n in mine:
        up = _closure(n.offset)
        for t in theirs:
            if n.offset in _closure(t.offset) or (up.get(t.offset, max_depth + 1) <= max_depth
                                                  and t.n_hyponyms <= MAX_HYPONYMS):
                return True
    return False


# WordNet senses too general to make a stand-in "of the same kind": everything is an object, a
# whole, an artifact, an organism... ("kangaroo" and "duck" share only "animal" and above).
GENERIC_KINDS = frozenset({
    "entity", "physical_entity", "abstraction", "thing", "object", "whole", "unit", "part", "portion",
    "natural_object", "causal_agent", "artifact", "artefact", "instrumentality", "instrumentation", "device",
    "container", "structure", "construction", "covering", "commodity", "equipment", "implement", "creation",
    "article", "material", "system", "living_thing", "organism", "being", "animal", "animate_being", "beast",
    "fauna", "chordate", "vertebrate", "craniate", "invertebrate", "person", "individual", "plant", "flora",
    "vascular_plant", "matter", "substance", "solid", "fluid", "liquid", "food", "nutrient", "nutriment",
    "foodstuff", "food_product", "produce", "green_goods", "solid_food", "plant_organ", "plant_part",
    "plant_structure", "natural_object",
})


def _meaningful(offset: int) -> bool:
    s = wordnet.synset(offset)
    return s is not None and not (set(s.lemmas) & GENERIC_KINDS)


def noun_sense_count(noun: str) -> int:
    """How many of the noun's senses `shared_kind(..., sense=)` can be asked about (0: unknown)."""
    return len(_noun_senses(noun)) if wordnet.available() else 0


def shared_kind(noun: str, text: str | None = None, category: str | None = None,
                sense: int = 0, tags: tuple[str, ...] = ()) -> tuple[int, str] | None:
    """How close a candidate (an asset's name `text`, or a generator `category`) is in kind to the
    noun: (steps from the noun's ranked visible sense number `sense` (0: the dominant one) up to
    the nearest meaningful sense both
    are kinds of, that sense's first lemma), or None when they share none (`GENERIC_KINDS` do not
    count) or WordNet does not know either."""
    if not wordnet.available():
        return None
    mine = _noun_senses(noun)
    if len(mine) <= sense:
        return None
    up = _closure(mine[sense].offset)
    theirs = [s.offset for s in (_text_senses(text, tuple(tags)) if text is not None else ())]
    if category is not None:
        theirs += sorted(_category_senses(category))
    best: tuple[int, int] | None = None
    for t in theirs:
        for off in _closure(t):
            d = up.get(off)
            if d is not None and (best is None or d < best[0]) and _meaningful(off):
                best = (d, off)
    if best is None:
        return None
    return best[0], wordnet.synset(best[1]).lemmas[0].replace("_", " ")


# -- what WordNet says a candidate is not ----------------------------------------------------------


# a kind shared this close above the noun makes a candidate a sibling (`contradicts`); farther up
# ("conveyance" for a locomotive and a train) WordNet's tree says too little to overrule similarity
SIBLING_DEPTH = 2


def _candidate_senses(text: str | None, category: str | None, tags: tuple[str, ...]) -> list[int]:
    """The senses a candidate shows: a generator category's (`_category_senses`), else its name's dominant one."""
    if category is not None:
        return sorted(_category_senses(category))
    return [x.offset for x in _text_senses(text, tags)] if text else []


def _is_linked(mine: tuple[wordnet.Synset, ...], theirs: list[int]) -> bool:
    """Whether one of the noun's senses is one of the candidate's, a kind of it, or the other way."""
    return any(n.offset in _closure(t) or t in _closure(n.offset) for n in mine for t in theirs)


def linked(noun: str, text: str | None = None, category: str | None = None,
           tags: tuple[str, ...] = ()) -> bool | None:
    """Whether a candidate (a name `text` or a generator `category`) is the noun's thing, a kind of it,
    or a thing the noun is a kind of ("Bedside table" for a nightstand, a table). None when WordNet
    is missing or knows either not as a visible thing."""
    mine = _noun_senses(noun) if wordnet.available() else ()
    theirs = _candidate_senses(text, category, tuple(tags)) if mine else []
    if not mine or not theirs:
        return None
    return _is_linked(mine, theirs)


def contradicts(noun: str, text: str | None = None, category: str | None = None,
                tags: tuple[str, ...] = ()) -> str | None:
    """Why WordNet says a candidate shows another thing than the noun however similar they are, or
    None. Not `linked`, and either a sibling (the noun's dominant sense and the candidate are kinds
    of one meaningful sense at most `SIBLING_DEPTH` steps above the noun: a stool and a chair are
    seats, "sibling of seat"; a locomotive and a train only conveyances, no sibling) or the noun a
    kind of another sense of a category's word than the one the category declares it builds
    (`Category.sense`: a light bulb is a lamp, the light source; the lamp category is the
    furniture: "another sense of lamp"). None without WordNet."""
    if linked(noun, text, category, tags) is not False:
        return None
    mine = _noun_senses(noun)
    up = _closure(mine[0].offset)
    theirs = _candidate_senses(text, category, tuple(tags))
    shared = [(d, off) for t in theirs for off in _closure(t) for d in [up.get(off)]
              if d is not None and d <= SIBLING_DEPTH and _meaningful(off)]
    if shared:
        return f"sibling of {wordnet.synset(min(shared)[1]).lemmas[0].replace('_', ' ')}"
    declared = category is not None and category in CATEGORIES and CATEGORIES[category].sense
    if declared and any(x.offset in up for x in wordnet.senses(category) if x.offset not in theirs):
        return f"another sense of {category}"
    return None


@lru_cache(maxsize=1024)
def synonym_sibling(word: str) -> str | None:
    """For a synonym of the rule vocabulary that WordNet says is another thing than its category
    ("stool" of the chair category: `contradicts`), why; None for the category's own name, its
    plural, a synonym that is a kind of it ("taxi" of car) and words WordNet does not know."""
    from .vocabulary import noun_to_category

    hit = noun_to_category(word)
    if hit is None or not wordnet.available():
        return None
    noun = singular(word) if hit[1] else word
    if noun == hit[0] or word == CATEGORIES[hit[0]].plural:
        return None
    return contradicts(noun, category=hit[0])
