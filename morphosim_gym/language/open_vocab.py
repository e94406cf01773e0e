"""Open vocabulary: a noun outside the rule vocabulary grounds to a basic shape or a real asset.

Basic shapes (`SHAPES`) always exist and ground by name ("a green cylinder"). Other candidates
come from tables that higher layers register (`register_candidates`): the generator registers
every real asset's name, category and tags as "asset:<id>" so that this layer never imports the
asset layer. `ground_open` compares the MiniLM embedding of "a <noun>" with every shape phrase and
registered text; `grounding.ground_noun` uses it when it beats the nearest library category.

Open categories ("cylinder", "asset:sweethome3d/.../teapot") are not in `vocabulary.CATEGORIES`
(whose iteration, and so the rule grounding, is unchanged) but index it with a generic entry.
"""

from __future__ import annotations

import re
import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import embeddings, hypernyms
from .hypernyms import head_word
from .vocabulary import singular

__all__ = ["ASSET_PREFIX", "OPEN_FLOOR", "SHAPES", "OpenMatch", "ground_named", "ground_open", "has_assets",
           "candidate_tags", "is_open_category", "name_words", "nearest_candidates", "register_candidates", "shape_for_word"]

ASSET_PREFIX = "asset:"
OPEN_FLOOR = 0.5          # cosine similarity an open candidate needs (made-up words stay below ~0.45)
NAME_FLOOR = 0.3          # ... when the noun's words are words of the candidate's name ("fan" -> "Ceiling fan")
# shape -> words that name it exactly
SHAPES: dict[str, tuple[str, ...]] = {
    "cylinder": ("cylinder", "cylinders", "tube", "pipe"),
    "sphere": ("sphere", "spheres", "orb", "globe"),
    "torus": ("torus", "tori", "donut shape", "ring shape"),
    "capsule": ("capsule", "capsules", "pill"),
    "pyramid": ("pyramid", "pyramids"),
    "disc": ("disc", "discs", "disk", "disks"),
    "plank": ("plank", "planks", "board", "beam"),
}
_WORD_TO_SHAPE = {w: s for s, words in SHAPES.items() for w in words}

# -> labels, texts, vectors [N, D], and optionally the words tagging each candidate [N] (an asset's tags)
CandidateTable = Callable[[], tuple]
_tables: dict[str, CandidateTable] = {}
_lock = threading.Lock()
_shape_table: list[np.ndarray] = []


@dataclass(frozen=True)
class OpenMatch:
    """A candidate for a noun: its category label, the text it matched and the cosine similarity."""

    category: str
    text: str
    similarity: float


def register_candidates(name: str, table: CandidateTable) -> None:
    """Add (or replace) a table of open candidates, called lazily on the first open grounding."""
    with _lock:
        _tables[name] = table


def is_open_category(category: str) -> bool:
    """A basic shape or an "asset:<id>" category."""
    return category in SHAPES or category.startswith(ASSET_PREFIX)


def shape_for_word(noun: str) -> str | None:
    """The basic shape a word names exactly ("disk" -> "disc"), else None."""
    return _WORD_TO_SHAPE.get(noun.strip().lower())


def _shape_vectors() -> np.ndarray:
    with _lock:
        if not _shape_table:
            _shape_table.append(embeddings.encode_table([f"a {s}" for s in SHAPES]))
        return _shape_table[0]


def _all_candidates() -> tuple[list[str], list[str], np.ndarray]:
    labels, texts, vecs, _ = _all_tagged()
    return labels, texts, vecs


def _all_tagged() -> tuple[list[str], list[str], np.ndarray, list[tuple[str, ...]]]:
    """Every candidate: labels, texts, vectors [N, D] and tags (empty for shapes and untagged tables)."""
    labels, texts, vecs = list(SHAPES), [f"a {s}" for s in SHAPES], [_shape_vectors()]
    tags: list[tuple[str, ...]] = [() for _ in SHAPES]
    for table in list(_tables.values()):
        lab, txt, v, *rest = table()
        if len(lab):
            labels += lab
            texts += txt
            vecs.append(np.asarray(v, dtype=np.float32))
            tags += [tuple(t) for t in rest[0]] if rest else [() for _ in lab]
    return labels, texts, np.concatenate(vecs), tags


def candidate_tags() -> dict[str, tuple[str, ...]]:
    """Candidate label -> the words tagging it (an asset's tags; none for shapes)."""
    labels, _, _, tags = _all_tagged()
    return {lab: t for lab, t in zip(labels, tags) if t}


def nearest_candidates(phrase: str, k: int = 5) -> list[OpenMatch]:
    """The `k` open candidates closest to "a <phrase>", best first."""
    labels, texts, vecs = _all_candidates()
    q = embeddings.embed([f"a {phrase}"])[0]
    sims = vecs @ q
    order = np.argsort(-sims, kind="stable")[:k]
    return [OpenMatch(labels[i], texts[i], round(float(sims[i]), 4)) for i in order]


def _words(text: str) -> set[str]:
    """The text's words with their singulars: crude ("sunglasses" -> "sunglasse") and the
    vocabulary's ("sunglasses" -> "sunglass")."""
    words = set(re.findall(r"[a-z0-9]+", text.lower()))
    return words | {w[:-1] for w in words if len(w) > 3 and w.endswith("s")} | {singular(w) for w in words}


def name_words(text: str) -> set[str]:
    """A candidate text's words with their singulars ("Sun glasses" -> sun, glass, glasses...)."""
    return _words(text)


def ground_open(phrase: str, floor: float = OPEN_FLOOR) -> OpenMatch | None:
    """The best open candidate for "a <phrase>": among those whose name holds the phrase's words
    (similarity >= `NAME_FLOOR`), else overall when it reaches `floor`; None when neither."""
    labels, texts, vecs = _all_candidates()
    sims = vecs @ embeddings.embed([f"a {phrase}"])[0]
    want = _words(phrase)
    named = [i for i, t in enumerate(texts) if want and want <= _words(t) and sims[i] >= NAME_FLOOR]
    pool = named or [int(np.argmax(sims))]
    best = max(pool, key=lambda i: (float(sims[i]), -i))
    if not named and sims[best] < floor:
        return None
    return OpenMatch(labels[best], texts[best], round(float(sims[best]), 4))


def has_assets() -> bool:
    """Whether any registered table has candidates (real assets are installed and allowed)."""
    return any(len(table()[0]) for table in list(_tables.values()))


def _compact(text: str) -> str:
    """The text's letters, each word singular ("Sun glasses" and "sunglass" -> "sunglass")."""
    return "".join(singular(w) for w in re.findall(r"[a-z]+", text.lower()))


# a name "<noun> <head>" shows the noun when both words are artifacts (WordNet's lexicographer file)
# and this similar: "Chandelier lamp" (0.53) for "chandelier", not "Dog house" or "Spider plant"
APPOSITION_FLOOR = 0.5
# an asset tag names it ("nightstand" on "Bedside table") when at most this many candidates carry it
# and the noun is this similar to the candidate's name
RARE_TAG = 3
TAG_NAME_FLOOR = 0.6


def _appositive(noun: str, text: str) -> bool:
    """Whether `text` is "... <noun> <head>" with `head` a near-synonym of the noun's kind."""
    words = re.findall(r"[a-z]+", text.lower())
    if len(words) < 2 or singular(words[-2]) != singular(noun) or "with" in words:
        return False
    if hypernyms.ranked_senses(" ".join(words[-2:])):
        return False   # a compound WordNet knows is a kind of its head: "Shower curtain" is a curtain
    mine, theirs = hypernyms.ranked_senses(singular(noun))[:1], hypernyms.ranked_senses(singular(words[-1]))[:1]
    if not mine or not theirs or not mine[0].lexfile == theirs[0].lexfile == "artifact":
        return False   # only made things: "Orange juice", "Tomato sauce", "Peach blossom" are not the noun
    v = embeddings.embed([f"a {noun}", f"a {words[-1]}"])
    return float(v[0] @ v[1]) >= APPOSITION_FLOOR


def _tag_named(noun: str, texts: list[str], tags: list[tuple[str, ...]], vecs: np.ndarray) -> list[int]:
    """Candidates a rare tag equal to the noun names, when the noun is close to their name."""
    want = {noun, singular(noun)}
    hits = [i for i, t in enumerate(tags) if want & {x.lower() for x in t}]
    if not hits or len(hits) > RARE_TAG:
        return []
    sims = vecs[hits] @ embeddings.embed([f"a {noun}"])[0]
    # a tag may narrow the name ("nightstand" on "Bedside table", a kind of table), never contradict it:
    # a "Towel" tagged "blanket" is no blanket when WordNet relates neither to the other
    return [i for i, s in zip(hits, sims) if float(s) >= TAG_NAME_FLOOR
            and hypernyms.linked(noun, text=texts[i], tags=tags[i]) is not False]


def ground_named(noun: str) -> OpenMatch | None:
    """The candidate named by the noun: its name is the noun ("Bunkbed" for "bunk bed"), or the
    noun's words are words of its name and its last word is the name's head noun ("Electric
    guitar" for "guitar", not "Spider plant" for "spider"), or the noun is the name's modifier and
    its head a near-synonym of the same kind ("Chandelier lamp", `_appositive`), or a rare tag of
    the candidate is the noun ("nightstand" on "Bedside table", `_tag_named`); an exact name first,
    then the most similar. None if none."""
    words = re.findall(r"[a-z0-9]+", noun.lower())
    if not words:
        return None
    labels, texts, vecs, tags = _all_tagged()
    want, head, compact = _words(noun), singular(words[-1]), _compact(noun)
    exact = [i for i, t in enumerate(texts) if _compact(t) == compact]
    named = exact or [i for i, t in enumerate(texts) if want <= _words(t) and head_word(t) == head]
    if not named and len(words) == 1:
        named = [i for i, t in enumerate(texts) if words[0] in _words(t) and _appositive(words[0], t)]
        named = named or _tag_named(words[0], texts, tags, vecs)
    if not named:
        return None
    sims = vecs[named] @ embeddings.embed([f"a {noun}"])[0]
    k = int(np.argmax(sims))
    return OpenMatch(labels[named[k]], texts[named[k]], round(float(sims[k]), 4))
