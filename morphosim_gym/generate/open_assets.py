"""Registers every installed real asset as an open-vocabulary candidate ("asset:<id>").

Imported by `compose` so that parsing a prompt after the generator is loaded can ground any
noun ("a teapot") to an asset by its name, category and tags (MiniLM embeddings, cached on disk).
Honours `$MORPHOSIM_ASSET_SOURCES` (empty: no asset candidates, shapes only).
"""

from __future__ import annotations

import numpy as np

from ..language import embeddings, open_vocab
from .real_assets import ASSET_PREFIX, asset_index, env_sources

__all__ = ["asset_candidate_table"]


def asset_candidate_table() -> tuple[list[str], list[str], np.ndarray, list[tuple[str, ...]]]:
    """Labels "asset:<id>", texts (names), embeddings and tags of every mesh or splat asset allowed here."""
    if env_sources() == ():
        return [], [], np.zeros((0, embeddings.EMBEDDING_DIM), dtype=np.float32), []
    index = asset_index()
    vecs = index.embeddings(embeddings.encode_table, embed_name=embeddings.MODEL_NAME)
    keep = [i for i, r in enumerate(index.records) if r.kind in ("mesh", "splat")]
    recs = [index.records[i] for i in keep]
    return [ASSET_PREFIX + r.id for r in recs], [r.name for r in recs], vecs[keep], [r.tags for r in recs]


open_vocab.register_candidates("assets", asset_candidate_table)
