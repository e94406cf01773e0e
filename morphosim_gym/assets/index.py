"""`AssetIndex`: every asset of every source, built once and cached on disk as JSON.

The cache holds one entry per source, keyed by a hash of the source's file stats (path, size,
mtime) and of its `selection` when it has one (the tables a source picks its assets by), so a
changed or newly installed source, or a changed selection, is re-read and the others are not.
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..scene.atomic import atomic_write_stream, atomic_write_text
from .errors import AssetWarning
from .record import AssetRecord
from .search import EmbedFn, rank
from .sources import AssetSource, default_sources

__all__ = ["INDEX_VERSION", "AssetIndex", "default_cache_dir"]

INDEX_VERSION = 1
INDEX_FILE = "index.json"


def default_cache_dir() -> Path:
    """`$MORPHOSIM_CACHE/assets`, else `~/.cache/morphosim_gym/assets`."""
    return Path(os.environ.get("MORPHOSIM_CACHE", Path.home() / ".cache" / "morphosim_gym")) / "assets"


def _source_key(src: AssetSource) -> str:
    return f"{src.name}:{getattr(src, 'folder', '')}"


def _fingerprint_hash(src: AssetSource) -> str:
    """The source's cache key: its file stats and, for a source that picks its assets by tables in
    the code (0 A.D.), its `selection` string, so that a changed table re-reads the unchanged files."""
    stats = [list(s) for s in src.fingerprint()]
    selection = str(getattr(src, "selection", ""))
    return hashlib.sha256(json.dumps([INDEX_VERSION, _source_key(src), stats, selection]).encode()).hexdigest()


def _read_cache(path: Path) -> dict:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return {}
    except (OSError, ValueError) as exc:
        warnings.warn(AssetWarning(f"Ignoring the damaged asset index {path} ({exc}); rebuilding it"), stacklevel=3)
        return {}
    if not isinstance(data, dict) or data.get("version") != INDEX_VERSION or not isinstance(data.get("sources"), dict):
        return {}
    return data["sources"]


def _load_vectors(path: Path | None, n: int) -> np.ndarray | None:
    if path is None or not path.exists():
        return None
    try:
        vecs = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        warnings.warn(AssetWarning(f"Ignoring damaged cached embeddings {path} ({exc})"), stacklevel=3)
        return None
    return vecs if vecs.ndim == 2 and len(vecs) == n and np.all(np.isfinite(vecs)) else None


def _entry_records(entry: object, fingerprint: str) -> list[AssetRecord] | None:
    """A cached source entry's records when its fingerprint is current and it parses, else None."""
    if not isinstance(entry, dict) or entry.get("fingerprint") != fingerprint:
        return None
    try:
        return [AssetRecord.from_dict(d) for d in entry["records"]]
    except (KeyError, TypeError, ValueError):
        return None


def _write_cache(path: Path, sources: dict) -> None:
    try:
        atomic_write_text(path, json.dumps({"version": INDEX_VERSION, "sources": sources}))
    except OSError as exc:
        warnings.warn(AssetWarning(f"Could not write the asset index cache {path} ({exc})"), stacklevel=3)


class AssetIndex:
    """The assets of some sources, with lookup, counts and search.

    Examples:
        >>> index = AssetIndex.load()                       # doctest: +SKIP
        >>> [r.id for r, _ in index.search("horse", k=3)]   # doctest: +SKIP
    """

    def __init__(self, records: Sequence[AssetRecord], cache_dir: str | os.PathLike | None = None) -> None:
        self.records: list[AssetRecord] = list(records)
        self.cache_dir = Path(cache_dir) if cache_dir is not None else None
        self._by_id = {r.id: r for r in self.records}
        if len(self._by_id) != len(self.records):
            dup = [i for i, n in Counter(r.id for r in self.records).items() if n > 1]
            raise ValueError(f"Expected unique asset ids, found duplicates {dup[:5]}")
        self._vectors: dict[EmbedFn, np.ndarray] = {}

    # -------------------------------------------------------------- building
    @classmethod
    def build(cls, sources: Sequence[AssetSource] | None = None, cache_dir: str | os.PathLike | None = None,
              *, refresh: bool = False) -> AssetIndex:
        """Index `sources` (default `default_sources()`), re-reading only sources whose files changed.

        Args:
            sources: where assets come from.
            cache_dir: where `index.json` lives (default `default_cache_dir()`); an unwritable
                folder only costs the caching (a warning).
            refresh: ignore the cached entries (they are rewritten).
        """
        sources = default_sources() if sources is None else list(sources)
        path = Path(cache_dir if cache_dir is not None else default_cache_dir()) / INDEX_FILE
        cached = {} if refresh else _read_cache(path)
        entries: dict[str, dict] = {}
        records: list[AssetRecord] = []
        for src in sources:
            key, fp = _source_key(src), _fingerprint_hash(src)
            recs = _entry_records(cached.get(key), fp)
            if recs is None:
                recs = src.records()
            entries[key] = {"fingerprint": fp, "records": [r.to_dict() for r in recs]}
            records.extend(recs)
        if any(cached.get(k) != v for k, v in entries.items()):
            _write_cache(path, {**cached, **entries})
        return cls(records, cache_dir=path.parent)

    load = build   # `AssetIndex.load()` reads as "the index, from the cache when it is current"

    # ---------------------------------------------------------------- lookup
    def __len__(self) -> int:
        return len(self.records)

    def __iter__(self):
        return iter(self.records)

    def __contains__(self, asset_id: object) -> bool:
        return asset_id in self._by_id

    def get(self, asset_id: str) -> AssetRecord:
        """The record with this id (`KeyError` naming close ids when there is none)."""
        try:
            return self._by_id[asset_id]
        except KeyError:
            close = [r.id for r in self.records if asset_id.lower() in r.id.lower()][:5]
            raise KeyError(f"No asset {asset_id!r}" + (f"; did you mean {close}?" if close else "")) from None

    def kind(self, kind: str) -> list[AssetRecord]:
        """The records of one kind ("mesh", "splat", "sky")."""
        return [r for r in self.records if r.kind == kind]

    def counts_by_source(self) -> dict[str, int]:
        return dict(sorted(Counter(r.source for r in self.records).items()))

    def counts_by_category(self) -> dict[str, int]:
        return dict(sorted(Counter(r.category for r in self.records).items()))

    # ---------------------------------------------------------------- search
    def embeddings(self, embed: EmbedFn, embed_name: str | None = None) -> np.ndarray:
        """Every record's `search_text` embedded by `embed`, computed once per function. [N, D]

        With `embed_name` (which names the model, e.g. "all-MiniLM-L6-v2") and a cache folder, the
        vectors are also stored on disk, keyed by the name and the texts.
        """
        if embed not in self._vectors:
            texts = [r.search_text for r in self.records]
            path = None
            if embed_name and self.cache_dir is not None:
                digest = hashlib.sha256(json.dumps([embed_name, texts]).encode()).hexdigest()[:32]
                path = self.cache_dir / f"embeddings-{digest}.npy"
            vecs = _load_vectors(path, len(texts))
            if vecs is None:
                vecs = np.asarray(embed(texts), dtype=np.float32)
                if vecs.ndim != 2 or len(vecs) != len(texts):
                    raise ValueError(f"Expected embed() to return [{len(texts)}, D], found {vecs.shape}")
                if path is not None:
                    try:
                        atomic_write_stream(path, lambda f: np.save(f, vecs))
                    except OSError as exc:
                        warnings.warn(AssetWarning(f"Could not cache embeddings in {path} ({exc})"), stacklevel=2)
            self._vectors[embed] = vecs
        return self._vectors[embed]

    def search(self, query: str | np.ndarray, k: int = 10, *, embed: EmbedFn | None = None,
               embed_name: str | None = None, kind: str | None = None) -> list[tuple[AssetRecord, float]]:
        """The `k` assets that best match `query` (text, or an embedding [D] with `embed`), best first.

        Without `embed`, only word and substring matches on name, category and tags count; with it,
        the cosine similarity of the query and each asset's text is added (`embed_name`: see
        `embeddings`).
        """
        vectors = self.embeddings(embed, embed_name) if embed is not None else None
        records = self.records
        if kind is not None:
            mask = np.array([r.kind == kind for r in records], dtype=bool)
            records = [r for r, m in zip(records, mask) if m]
            vectors = vectors[mask] if vectors is not None else None
        return rank(query, records, k, vectors=vectors, embed=embed)
