"""Feature-field latents for Gaussians added after the fit (video layers, a background plate): the
latent of each object that the semantic decoder reads most clearly as that object's name.

The mean latent of an object's Gaussians is a blend: where the object is small in the frames (a
few walkers over a large street) most of its Gaussians learned features mixed with the setting's,
and the mean decodes as the setting, so an edit of "the person" then selects none of the added
Gaussians. `object_prototypes` instead ranks the object's Gaussians by how far their decoded
similarity to the object's own name beats the best other name (the margin), and averages the top
`share` of them; when even that average does not decode as the object, it takes the single
Gaussian with the largest margin, searched over all Gaussians when the object's own have none.
When no Gaussian at all reads as the object (a fast cyclist the fit never drew: every latent
decodes as the street), or, with an "instance" decoder, the chosen latent reads as another
instance, the latent is steered (`steer_latent`: a few gradient steps through the frozen
decoders) until it decodes as the object's name and instance code: the target a distillation of
the object's mask pixels would have given the added Gaussians.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..scene import FeatureDecoder, Gaussians, SceneObject, instance_codes

__all__ = ["name_margins", "code_margins", "object_prototypes", "steer_latent"]


def name_margins(decoder: FeatureDecoder, latents: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """[N, P] decoded cosine similarity of each latent to each name minus its best similarity to
    the other names (> 0: the latent reads as that name)."""
    return _margins(decoder.similarity(np.asarray(latents, np.float32), embeddings_of(names)))


def _margins(s: np.ndarray) -> np.ndarray:
    out = np.empty_like(s)
    for j in range(s.shape[1]):
        out[:, j] = s[:, j] - np.delete(s, j, axis=1).max(axis=1) if s.shape[1] > 1 else s[:, j]
    return out


def code_margins(decoder: FeatureDecoder, latents: np.ndarray, ids: Sequence[int]) -> np.ndarray:
    """[N, P] decoded similarity of each latent to each instance's code minus its best to the others'."""
    return _margins(decoder.similarity(np.asarray(latents, np.float32), instance_codes(list(ids), decoder.out_dim)))


def steer_latent(latent: np.ndarray, targets: Sequence[tuple[FeatureDecoder, np.ndarray, int]], steps: int = 150,
                 lr: float = 0.05, temperature: float = 0.1) -> np.ndarray:
    """`latent` [D] moved by Adam steps so that each (decoder, target rows [P, D_s], index) decodes
    nearest its target row `index` (softmax cross-entropy over the rows at `temperature`, summed)."""
    import torch

    z = torch.tensor(np.asarray(latent, np.float32), requires_grad=True)
    layers = [[(torch.from_numpy(w), torch.from_numpy(b)) for w, b in zip(dec.weights, dec.biases)]
              for dec, _, _ in targets]
    rows = [torch.from_numpy(np.asarray(t, np.float32)) for _, t, _ in targets]
    opt = torch.optim.Adam([z], lr=lr)
    for _ in range(steps):
        loss = z.sum() * 0.0
        for (dec, _, j), lay, t in zip(targets, layers, rows):
            h = z
            for k, (w, b) in enumerate(lay):
                h = h @ w + b
                if k < len(lay) - 1:
                    h = torch.relu(h)
            if dec.normalize:
                h = h / h.norm().clamp(min=1e-12)
            loss = loss - torch.log_softmax(h @ t.T / temperature, dim=0)[j]
        opt.zero_grad()
        loss.backward()
        opt.step()
    return z.detach().numpy().astype(np.float32)


def object_prototypes(g: Gaussians, objects: Sequence[SceneObject], decoder: FeatureDecoder | None,
                      share: float = 0.05, instance: FeatureDecoder | None = None) -> dict[int, np.ndarray]:
    """{object id: [D] latent} for every object (see the module docstring); without a decoder,
    the mean latent of the object's Gaussians (of all Gaussians for an object that has none).
    `instance`: the field's instance decoder, if any (the prototype must read as the object's code
    too). Empty when `g` carries no features."""
    if g.features is None or len(g) == 0:
        return {}
    f = np.asarray(g.features, np.float32)
    ids = np.asarray(g.object_ids)
    if not 0.0 < share <= 1.0:
        raise ValueError(f"Expected share in (0, 1], found {share!r}")
    if decoder is None or len(objects) < 2:
        return {o.id: (f[ids == o.id] if (ids == o.id).any() else f).mean(axis=0) for o in objects}
    names = embeddings_of([o.name for o in objects])                      # [P, 384], once
    codes = None if instance is None else instance_codes([o.id for o in objects], instance.out_dim)
    margins = _margins(decoder.similarity(f, names))

    def reads(z: np.ndarray, j: int) -> bool:
        return bool(_margins(decoder.similarity(z[None], names))[0, j] > 0
                    and (codes is None or _margins(instance.similarity(z[None], codes))[0, j] > 0))

    out: dict[int, np.ndarray] = {}
    for j, o in enumerate(objects):
        own = np.flatnonzero(ids == o.id)
        pool = own if len(own) else np.arange(len(f))
        top = pool[np.argsort(-margins[pool, j])[:max(1, int(round(share * len(pool))))]]
        mean = f[top].mean(axis=0)
        if reads(mean, j):
            out[o.id] = mean
            continue
        best = f[int(np.argmax(margins[:, j])) if margins[pool, j].max() <= 0 else int(top[0])]
        if not reads(best, j):
            targets = [(decoder, names, j)]
            if codes is not None:
                targets.append((instance, codes, j))
            best = steer_latent(best, targets)
        out[o.id] = best
    return out


def embeddings_of(names: Sequence[str]) -> np.ndarray:
    """[P, 384] sentence embeddings of `names` (the semantic decoder's target space)."""
    from ..language import embeddings

    return embeddings.embed(list(names))
