"""Feature-field latents for Gaussians added after the fit (video layers, a background plate): the
latent of each object that the semantic decoder reads most clearly as that object's name.

The mean latent of an object's Gaussians is a blend: where the object is small in the frames (a
few walkers over a large street) most of its Gaussians learned features mixed with the setting's,
and the mean decodes as the setting, so an edit of "the person" then selects none of the added
Gaussians. `object_prototypes` instead ranks the object's Gaussians by how far their decoded
similarity to the object's own name beats the best other name (the margin), and averages the top
`share` of them; when even that average does not decode as the object, it takes the single
Gaussian with the largest margin, searched over all Gaussians when the object's own have none.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..scene import FeatureDecoder, Gaussians, SceneObject

__all__ = ["name_margins", "object_prototypes"]


def name_margins(decoder: FeatureDecoder, latents: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """[N, P] decoded cosine similarity of each latent to each name minus its best similarity to
    the other names (> 0: the latent reads as that name)."""
    from ..language import embeddings

    s = decoder.similarity(np.asarray(latents, np.float32), embeddings.embed(list(names)))
    out = np.empty_like(s)
    for j in range(s.shape[1]):
        out[:, j] = s[:, j] - np.delete(s, j, axis=1).max(axis=1) if s.shape[1] > 1 else s[:, j]
    return out


def object_prototypes(g: Gaussians, objects: Sequence[SceneObject], decoder: FeatureDecoder | None,
                      share: float = 0.05) -> dict[int, np.ndarray]:
    """{object id: [D] latent} for every object (see the module docstring); without a decoder,
    the mean latent of the object's Gaussians (of all Gaussians for an object that has none).
    Empty when `g` carries no features."""
    if g.features is None or len(g) == 0:
        return {}
    f = np.asarray(g.features, np.float32)
    ids = np.asarray(g.object_ids)
    if not 0.0 < share <= 1.0:
        raise ValueError(f"Expected share in (0, 1], found {share!r}")
    if decoder is None or len(objects) < 2:
        return {o.id: (f[ids == o.id] if (ids == o.id).any() else f).mean(axis=0) for o in objects}
    names = [o.name for o in objects]
    margins = name_margins(decoder, f, names)
    out: dict[int, np.ndarray] = {}
    for j, o in enumerate(objects):
        own = np.flatnonzero(ids == o.id)
        pool = own if len(own) else np.arange(len(f))
        top = pool[np.argsort(-margins[pool, j])[:max(1, int(round(share * len(pool))))]]
        mean = f[top].mean(axis=0)
        if name_margins(decoder, mean[None], names)[0, j] > 0:
            out[o.id] = mean
            continue
        best = int(np.argmax(margins[:, j])) if margins[pool, j].max() <= 0 else int(top[0])
        out[o.id] = f[best]
    return out
