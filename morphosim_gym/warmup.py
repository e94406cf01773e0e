"""`morphosim warmup`: compile (and cache on disk) every numba kernel before first use.

The CPU renderer, the scene's motion skinning and the agents' skins are numba kernels compiled
with ``cache=True``: the first process on a machine pays about a minute of CPU compiling them
(``pip install`` compiles nothing), every later process loads them from numba's cache (next to
the sources, or in ``$NUMBA_CACHE_DIR``) in well under a second. `warm_up` runs a small job of
each variant once, so that the first env step, edit or render the user makes is fast:

    morphosim warmup                     # ~1-2 min once; then the envs step within seconds

Variants: forward rendering in float32 (the hot path), with and without the feature channels;
the backward pass (fitting); motion skinning in one chunk and in parallel chunks; and the three
envs (reset and one step, which also covers the agents' skins and each task's own path).
float64 rendering (gradient checks in the tests only) is left to compile on demand.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from typing import Callable, Optional, Sequence

import numpy as np

__all__ = ["WarmupStep", "warm_up", "STEPS", "register"]

PROMPT = "a red ball bounces from right to left"


@dataclass(frozen=True)
class WarmupStep:
    """One warm-up job and how long it took (compiling, or loading from the cache)."""

    name: str
    seconds: float


def _scene(detail: float = 1.0):
    from morphosim_gym.generate.compose import GenerationConfig
    from morphosim_gym.pipeline import MorphoSim

    sim = MorphoSim(reconstruction="oracle", generation=GenerationConfig(detail=detail))
    return sim.generate(PROMPT, seed=0)


def _render_forward() -> None:
    from morphosim_gym.render.api import render

    scene = _scene()
    cam = scene.camera.resized(64, 48)
    render(scene, cam, 0.5)
    g = scene.at(0.5)
    feats = np.zeros((len(g), 4), np.float32)
    render(g.replace(features=feats), cam, features=True)


def _render_backward() -> None:
    import torch

    from morphosim_gym.render.api import render

    scene = _scene(detail=0.3)
    g = scene.at(0.0).torch()
    colors = g.colors.clone().requires_grad_(True)
    out = render(g.replace(colors=colors), scene.camera.resized(32, 24))
    torch.as_tensor(out.rgb).sum().backward()


def _skinning() -> None:
    from morphosim_gym.scene.motion import _SKIN_CHUNK

    small, large = _scene(detail=0.05), _scene()
    small.at(0.3)                                   # one chunk
    if len(large.gaussians) <= _SKIN_CHUNK:         # parallel chunks (a default-detail scene has more)
        raise RuntimeError(f"Expected more than {_SKIN_CHUNK} Gaussians to compile the parallel skinning, "
                           f"found {len(large.gaussians)}")
    large.at(0.3)


def _fit_ssim() -> None:
    import torch

    from morphosim_gym.reconstruct.fused_ssim import fused_ssim_loss

    pred = torch.rand(24, 32, 3).requires_grad_(True)
    fused_ssim_loss(pred, torch.rand(24, 32, 3)).backward()


def _env(env_id: str) -> Callable[[], None]:
    def run() -> None:
        import gymnasium as gym

        import morphosim_gym.envs  # noqa: F401  (registers the envs)

        env = gym.make(env_id)
        try:
            env.reset(seed=0)
            env.step(env.action_space.sample())
        finally:
            env.close()
    return run


#: (name, job) in the order they run
STEPS: tuple[tuple[str, Callable[[], None]], ...] = (
    ("render: forward float32, with and without features", _render_forward),
    ("render: backward (fitting)", _render_backward),
    ("scene motion: skinning, one chunk and parallel", _skinning),
    ("reconstruct: the fit's SSIM loss, forward and backward", _fit_ssim),
    ("env MorphoSim/Track-v0: reset + step", _env("MorphoSim/Track-v0")),
    ("env MorphoSim/Reach-v0: reset + step (arm skin)", _env("MorphoSim/Reach-v0")),
    ("env MorphoSim/Find-v0: reset + step", _env("MorphoSim/Find-v0")),
)


def warm_up(steps: Optional[Sequence[str]] = None,
            report: Optional[Callable[[WarmupStep], None]] = None) -> list[WarmupStep]:
    """Run the warm-up jobs (all, or those whose name contains one of `steps`); `report` is called
    after each. Returns what ran and how long each took."""
    chosen = [(n, f) for n, f in STEPS if not steps or any(s.lower() in n.lower() for s in steps)]
    if not chosen:
        raise ValueError(f"Expected a warm-up step among {[n for n, _ in STEPS]}, found {list(steps or [])}")
    done = []
    for name, job in chosen:
        start = time.perf_counter()
        job()
        step = WarmupStep(name, time.perf_counter() - start)
        done.append(step)
        if report is not None:
            report(step)
    return done


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `warmup` subcommand."""
    p = sub.add_parser("warmup", help="compile and cache every numba kernel once (first use then takes seconds)",
                       description="Run a small render, skinning, fitting step and env step of every variant so "
                                   "that numba compiles its kernels into its on-disk cache now, not at first use.")
    p.add_argument("--only", action="append", default=[], metavar="WORD",
                   help="run only the steps whose name contains WORD (repeatable), e.g. --only Track")
    p.set_defaults(func=_main)


def _main(args: argparse.Namespace) -> int:
    import numba

    where = numba.config.CACHE_DIR or "numba's default cache (__pycache__ beside the sources)"
    print(f"morphosim warmup: compiling numba kernels into {where} (numba {numba.__version__}) ...", flush=True)
    start = time.perf_counter()
    steps = warm_up(args.only or None, report=lambda s: print(f"  {s.seconds:7.1f} s  {s.name}", flush=True))
    print(f"morphosim warmup: {len(steps)} steps in {time.perf_counter() - start:.1f} s; later processes load the "
          f"kernels from the cache", flush=True)
    return 0
