"""A small reader of Princeton WordNet's noun files: senses and "is a kind of" (hypernyms).

Reads Debian's `wordnet-base` files (`/usr/share/wordnet/index.noun`, `data.noun`; another folder
with `$MORPHOSIM_WORDNET`). When they are not there, `available()` is False and every query
answers "unknown" (None), so grounding falls back to embeddings alone.

    >>> is_kind_of("eagle", "bird")                     # doctest: +SKIP
    True
"""

from __future__ import annotations

import os
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["DEFAULT_DIR", "PHYSICAL_LEXFILES", "Synset", "available", "hypernym_closure", "is_visible_noun",
           "sense_counts", "senses", "synset"]

DEFAULT_DIR = "/usr/share/wordnet"
ENV_VAR = "MORPHOSIM_WORDNET"
MAX_DEPTH = 24                        # WordNet noun hierarchies are at most ~20 deep
# lexicographer files of things one can see: animal, artifact, food, object, person, plant
LEXFILES = {5: "animal", 6: "artifact", 13: "food", 17: "object", 18: "person", 20: "plant"}
PHYSICAL_LEXFILES = frozenset(LEXFILES.values())


@dataclass(frozen=True)
class Synset:
    """One noun sense: its byte offset in `data.noun`, lexicographer file, lemmas, hypernym offsets
    and how many direct hyponyms (more specific senses) it has."""

    offset: int
    lexfile: str
    lemmas: tuple[str, ...]
    hypernyms: tuple[int, ...]
    gloss: str
    n_hyponyms: int = 0


_lock = threading.Lock()
_state: dict[str, Any] = {}          # "index": index.noun's bytes; "lines": lemma -> its line (or None)
_synsets: dict[int, Synset] = {}
_counts: dict[str, dict[str, dict[int, int]]] = {}


def _folder() -> Path:
    return Path(os.environ.get(ENV_VAR, DEFAULT_DIR))


def _index_bytes() -> bytes:
    """`index.noun` as bytes, read once (b"" without the file)."""
    with _lock:
        if "index" not in _state:
            try:
                _state["index"] = b"\n" + (_folder() / "index.noun").read_bytes()
            except OSError:
                _state["index"] = b""
        return _state["index"]


def _index_line(lemma: str) -> str | None:
    """The `index.noun` line of a lemma, or None; each lemma is searched for once (a miss scans
    the whole 4.7 MB file: ~4 ms, and the parser asks about every "-ly" word)."""
    data = _index_bytes()
    lines = _state.setdefault("lines", {})
    if lemma in lines:
        return lines[lemma]
    key = b"\n" + lemma.encode("latin-1", "replace") + b" "
    at = data.find(key)
    end = data.find(b"\n", at + 1) if at >= 0 else -1
    line = None if at < 0 else data[at + 1:end if end >= 0 else len(data)].decode("latin-1")
    lines[lemma] = line
    return line


def _offsets(line: str) -> tuple[int, ...]:
    """The synset offsets of an `index.noun` line, most frequent sense first."""
    parts = line.split()
    try:
        n_syn, n_ptr = int(parts[2]), int(parts[3])
        return tuple(int(x) for x in parts[6 + n_ptr:6 + n_ptr + n_syn])
    except (ValueError, IndexError):
        return ()


def available() -> bool:
    """Whether the WordNet noun files are installed and readable."""
    return bool(_index_bytes())


def synset(offset: int) -> Synset | None:
    """The sense at `offset` in `data.noun` (None when unreadable)."""
    with _lock:
        hit = _synsets.get(offset)
    if hit is not None:
        return hit
    try:
        with open(_folder() / "data.noun", "rb") as f:
            f.seek(offset)
            line = f.readline().decode("latin-1")
        head, _, gloss = line.partition(" | ")
        parts = head.split()
        n_words = int(parts[3], 16)
        lemmas = tuple(parts[4 + 2 * i].lower() for i in range(n_words))
        at = 4 + 2 * n_words
        n_ptr = int(parts[at])
        ptrs = [parts[at + 1 + 4 * i:at + 5 + 4 * i] for i in range(n_ptr)]
        hyper = tuple(int(p[1]) for p in ptrs if p[0] in ("@", "@i") and p[2] == "n")
        n_hypo = sum(1 for p in ptrs if p[0] in ("~", "~i"))
        syn = Synset(offset, LEXFILES.get(int(parts[1]), parts[1]), lemmas, hyper, gloss.strip(), n_hypo)
    except (OSError, ValueError, IndexError):
        return None
    with _lock:
        _synsets[offset] = syn
    return syn


def senses(noun: str, limit: int | None = None) -> list[Synset]:
    """The noun's senses, most frequent first ("fire hydrant" is looked up as "fire_hydrant", else
    as "fire-hydrant": "go kart" is WordNet's "go-kart")."""
    key = "_".join(noun.strip().lower().split())
    line = _index_line(key) if key else None
    if line is None and "_" in key:
        line = _index_line(key.replace("_", "-"))
    offsets = _offsets(line) if line else ()
    return [s for s in (synset(o) for o in offsets[:limit]) if s is not None]


def is_visible_noun(noun: str) -> bool:
    """Whether WordNet knows `noun` (or its "-s"/"-es" singular) as a thing one can see (a sense in
    `PHYSICAL_LEXFILES`); False without WordNet. Reads no embedding model."""
    forms = [noun] + ([noun[:-1]] if noun.endswith("s") else []) + ([noun[:-2]] if noun.endswith("es") else [])
    return any(s.lexfile in PHYSICAL_LEXFILES for f in forms for s in senses(f))


def _counts_table() -> dict[str, dict[int, int]]:
    """`cntlist.rev` read once: noun lemma -> {sense number (1 = first in `index.noun`): times tagged}."""
    with _lock:
        if "counts" not in _counts:
            table: dict[str, dict[int, int]] = {}
            try:
                text = (_folder() / "cntlist.rev").read_text(encoding="latin-1")
            except OSError:
                text = ""
            for line in text.splitlines():
                parts = line.split()
                lemma, _, rest = parts[0].partition("%") if len(parts) == 3 else ("", "", "")
                if rest.startswith("1:") and parts[1].isdigit() and parts[2].isdigit():
                    table.setdefault(lemma.lower(), {})[int(parts[1])] = int(parts[2])
            _counts["counts"] = table
        return _counts["counts"]


def sense_counts(noun: str) -> tuple[int, ...]:
    """How often each of the noun's senses (in `senses` order) was tagged in WordNet's corpus
    (`cntlist.rev`; 0 for untagged senses, all 0 without the file)."""
    key = "_".join(noun.strip().lower().split())
    line = _index_line(key) if key else None
    if line is None and "_" in key:
        key = key.replace("_", "-")
        line = _index_line(key)
    n = len(_offsets(line)) if line else 0
    counts = _counts_table().get(key, {})
    return tuple(counts.get(i + 1, 0) for i in range(n))


def hypernym_closure(sense: Synset) -> dict[int, int]:
    """Every more general sense of `sense` (itself included) -> its distance in hypernym steps."""
    out = {sense.offset: 0}
    frontier = [sense]
    for depth in range(1, MAX_DEPTH + 1):
        nxt = []
        for s in frontier:
            for off in s.hypernyms:
                if off not in out:
                    out[off] = depth
                    parent = synset(off)
                    if parent is not None:
                        nxt.append(parent)
        if not nxt:
            break
        frontier = nxt
    return out
