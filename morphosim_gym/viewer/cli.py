"""`morphosim view`: the browser viewer of a scene (or of an env's episode)."""

from __future__ import annotations

import argparse
from typing import Any

from ..extras import require_extra
from ..language.grounding_cli import add_grounding_flags, grounding_from_args
from ..policies import POLICY_SPEC_HELP

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `view` subcommand."""
    p = sub.add_parser(
        "view", help="open a scene, a prompt or an env in the browser viewer",
        description="Serve an interactive 4D viewer on a local web page: the scene rendered by our renderer, "
                    "a time slider, orbit/pan/zoom, a command box for edits and new prompts with undo, object "
                    "visibility and video recording. With --env, watch an episode of an env with a policy.")
    p.add_argument("source", nargs="?", default=None,
                   help="a scene file (.msim), a `morphosim generate --out` directory, or a prompt to generate "
                        "(with --env: the prompt of every episode's scene)")
    p.add_argument("--env", default=None, help="watch an env instead, e.g. MorphoSim/Track-v0")
    p.add_argument("--env-option", action="append", default=[], metavar="KEY=VALUE",
                   help="with --env: a keyword argument of gym.make, value read as YAML (repeatable), "
                        "e.g. --env-option width=128")
    p.add_argument("--policy", default="random", metavar="SPEC",
                   help=f"with --env: {POLICY_SPEC_HELP} (default: random)")
    p.add_argument("--episodes", type=int, default=0, help="with --env: stop after this many episodes (0: never)")
    p.add_argument("--seed", type=int, default=0, help="seed of generated scenes (and of env resets)")
    p.add_argument("--reconstruction", choices=["oracle", "fit"], default="oracle",
                   help="how prompts become scenes: 'oracle' (the generator's ground truth, instant; default) "
                        "or 'fit' (reconstructed from the generated clip, minutes)")
    p.add_argument("--detail", type=float, default=None,
                   help="Gaussian budget multiplier of generated scenes (default 1; with --env, the env's default)")
    add_grounding_flags(p)
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default: this machine only)")
    p.add_argument("--port", type=int, default=8080, help="port (the next free one if taken; 0: any)")
    p.add_argument("--resolution", type=int, default=512, help="longer side of streamed frames, pixels")
    p.add_argument("--record-dir", default="morphosim_recordings", help="where recorded videos go")
    p.add_argument("--quiet", action="store_true", help="no server banner")
    p.set_defaults(func=_view)


def _view(args: argparse.Namespace) -> int:
    require_extra("viewer", "viser", needed_for="morphosim view")      # before any scene or env is made
    from ..generate.compose import GenerationConfig
    from ..pipeline import MorphoSim
    from ..policies import resolve_policy

    if args.env is None and args.source is None:
        raise ValueError("Expected a scene file, a directory or a prompt to view (or --env ID), found none")
    if args.env is not None:
        from .app import import_viser
        from .env_app import EnvViewer

        import_viser()
        policy = resolve_policy(args.policy)        # a bad spec fails before the env is made
        kwargs = _env_options(args.env_option)
        if args.source is not None:
            kwargs["prompt"] = args.source
        if args.detail is not None or args.reconstruction != "oracle":
            kwargs.setdefault("sim", _env_sim(args.detail, args.reconstruction))
        print(f"morphosim view: making {args.env} ...", flush=True)
        viewer = EnvViewer(args.env, policy=policy, seed=args.seed,
                           episodes=args.episodes, env_kwargs=kwargs, host=args.host, port=args.port,
                           long_side=args.resolution, verbose=not args.quiet)
        print(f"morphosim view: {args.env} with the {args.policy} policy at {viewer.url} (Ctrl-C to stop)",
              flush=True)
        viewer.serve_forever()
        return 0

    if args.env_option:
        raise ValueError("Expected --env-option only with --env, found it without")
    from .app import SceneViewer, import_viser
    from .session import ViewerSession

    import_viser()                                  # fail before generating anything
    detail = 1.0 if args.detail is None else args.detail
    sim = MorphoSim(reconstruction=args.reconstruction, generation=GenerationConfig(detail=detail),
                    grounding=grounding_from_args(args))
    print("morphosim view: preparing the scene ...", flush=True)
    session = ViewerSession.from_source(args.source, sim=sim, seed=args.seed)
    session.warm_up()
    viewer = SceneViewer(session, host=args.host, port=args.port, long_side=args.resolution,
                         record_dir=args.record_dir, verbose=not args.quiet)
    scene = session.scene
    print(f"morphosim view: {', '.join(scene.object_names)} ({len(scene.gaussians)} Gaussians, "
          f"{scene.duration:g} s) at {viewer.url} (Ctrl-C to stop)", flush=True)
    viewer.serve_forever()
    return 0


def _env_sim(detail: float | None, reconstruction: str) -> Any:
    """The env's world for --detail / --reconstruction: the envs' default with those changed."""
    from dataclasses import replace

    from ..envs.config import DEFAULT_SIM_CONFIG

    generation = DEFAULT_SIM_CONFIG.generation if detail is None else replace(DEFAULT_SIM_CONFIG.generation,
                                                                              detail=detail)
    return replace(DEFAULT_SIM_CONFIG, reconstruction=reconstruction, generation=generation)


def _env_options(items: list[str]) -> dict:
    from ..config_yaml import load_yaml_text

    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip().isidentifier():
            raise ValueError(f"Expected --env-option KEY=VALUE, found {item!r}")
        out[key.strip()] = load_yaml_text(value, f"--env-option {key.strip()}")
    return out
