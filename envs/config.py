"""`EnvConfig`: every constructor argument of the MorphoSim envs, its type, default and check.

It is the one place the arguments are written down: the envs take `**kwargs` and build an
`EnvConfig` from them (`EnvConfig.from_kwargs`), `env_signature` turns its fields into the
`__signature__` that `help()` and `inspect.signature` show, and the tests compare each env's
docstring Arguments table against its fields. The world's own settings (detail,
reconstruction, caching) are not env arguments: they belong to `sim`, a `MorphoSim` or a
`SimConfig` (default `DEFAULT_SIM_CONFIG`).
"""

from __future__ import annotations

import inspect
import math
import os
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, Callable, Mapping, Optional

import numpy as np

from morphosim_gym.generate.compose import GenerationConfig
from morphosim_gym.pipeline import SimConfig
from morphosim_gym.scene import Scene4D

from .scene_file import check_scene_arg

from .pool import POOL_BACKENDS

if TYPE_CHECKING:  # pragma: no cover
    from morphosim_gym.pipeline import MorphoSim
    from morphosim_gym.tasks import TaskSpec

__all__ = ["EnvConfig", "DEFAULT_SIM_CONFIG", "ON_EDIT_ERROR", "RENDER_MODES", "MOVED_TO_SIM", "env_signature",
           "make_sim", "check_int"]

ON_EDIT_ERROR = ("raise", "skip")
RENDER_MODES = ("rgb_array",)
MOVED_TO_SIM = ("detail", "reconstruction")
DEFAULT_SIM_CONFIG = SimConfig(reconstruction="oracle", generation=GenerationConfig(detail=0.35))
"""The envs' world when `sim` is None: the generator's ground truth at 0.35 detail (as sharp as
0.5 at 84 px, ~25% faster)."""


def check_int(value: Any, name: str, low: int = 0) -> int:
    """`value` as an int >= `low`; `ValueError` naming `name` otherwise (bools are not integers)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) < low:
        raise ValueError(f"Expected {name} as an integer >= {low}, found {value!r}")
    return int(value)


def _size(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 8 <= int(value) <= 1024:
        raise ValueError(f"Expected {name} as an integer in [8, 1024], found {value!r}")
    return int(value)


def _rate(name: str, value: Any) -> float:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and 0.5 <= value <= 100):
        raise ValueError(f"Expected {name} in [0.5, 100], found {value!r}")
    return float(value)


def _one_of(choices: tuple, none_ok: bool = False) -> Callable[[str, Any], Any]:
    def check(name: str, value: Any) -> Any:
        if value not in choices and not (none_ok and value is None):
            shown = f"{list(choices)} or None" if none_ok else f"{choices}"
            raise ValueError(f"Expected {name} in {shown}, found {value!r}")
        return value

    return check


def _prompt(name: str, value: Any) -> Optional[str]:
    if value is not None and (not isinstance(value, str) or not value.strip()):
        raise ValueError(f"Expected {name} as a non-empty string, found {value!r}")
    return value


def _int(low: int, none_ok: bool = True) -> Callable[[str, Any], Optional[int]]:
    def check(name: str, value: Any) -> Optional[int]:
        return None if value is None and none_ok else check_int(value, name, low)

    return check


def _cameras(name: str, value: Any) -> Optional[tuple]:
    return None if value is None else tuple(value)


def _sim(name: str, value: Any) -> Any:
    if not (value is None or isinstance(value, SimConfig) or hasattr(value, "generate")):
        raise ValueError(f"Expected {name} as a MorphoSim, a SimConfig or None, found {type(value).__name__}")
    return value


def _seconds(name: str, value: Any) -> Optional[float]:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise ValueError(f"Expected {name} as a number of seconds > 0 or None, found {value!r}")
    return float(value)


def _flag(name: str, value: Any) -> bool:
    return bool(value)


_CHECKS: dict[str, Callable[[str, Any], Any]] = {     # in the order the errors are reported
    "width": _size, "height": _size, "render_width": _size, "render_height": _size,
    "control_hz": _rate,
    "render_mode": _one_of(RENDER_MODES, none_ok=True),
    "on_edit_error": _one_of(ON_EDIT_ERROR),
    "prompt": _prompt,
    "scene_seed": _int(0), "scene_pool": _int(1), "pool_seed": _int(0, none_ok=False), "pool_workers": _int(1),
    "pool_backend": _one_of(POOL_BACKENDS), "pool_timeout_s": _seconds, "render_threads": _int(1),
    "render_lod": _flag,
    "cameras": _cameras,
    "scene": check_scene_arg,
    "sim": _sim,
    "depth": _flag, "segmentation": _flag, "terminate_on_success": _flag,
}
"""Field -> check: the checked, normalised value or an "Expected ..., found ..." `ValueError`."""


@dataclass(frozen=True)
class EnvConfig:
    """The arguments of a MorphoSim env (see each env's Arguments table for their meaning).

    Construction checks every value with an "Expected ..., found ..." `ValueError` and stores
    them normalised (ints as `int`, `cameras` as a tuple). Checks that need the task or the
    rig (the task's kind, the rig's camera names) are the env's.
    """

    task: str | TaskSpec | dict | None = None
    prompt: str | None = None
    target: str | None = None
    scene: str | os.PathLike | Scene4D | None = None
    scene_seed: int | None = None
    scene_pool: int | None = None
    pool_seed: int = 0
    pool_workers: int | None = 1
    pool_backend: str = "process"
    pool_timeout_s: float | None = None
    width: int = 84
    height: int = 84
    depth: bool = False
    segmentation: bool = False
    cameras: tuple[str, ...] | None = None
    control_hz: float = 10.0
    render_agent: bool | None = None
    terminate_on_success: bool = False
    on_edit_error: str = "raise"
    render_mode: str | None = None
    render_width: int = 256
    render_height: int = 256
    render_threads: int | None = 1
    render_lod: bool = False
    sim: MorphoSim | SimConfig | None = None
    task_params: dict | None = None

    def __post_init__(self) -> None:
        for name, check in _CHECKS.items():
            object.__setattr__(self, name, check(name, getattr(self, name)))
        if self.scene is not None and (self.prompt is not None or self.scene_pool is not None):
            given = "prompt" if self.prompt is not None else "scene_pool"
            raise ValueError(f"Expected either scene (one fixed world) or {given}, found both "
                             f"(scene={self.scene!r}, {given}={getattr(self, given)!r})")

    @classmethod
    def from_kwargs(cls, kwargs: Mapping[str, Any], defaults: Optional[Mapping[str, Any]] = None) -> "EnvConfig":
        """The config of an env's keyword arguments over its per-env `defaults`; `TypeError` for an
        unknown argument (with the way to go for the world's settings, which moved to `sim`)."""
        moved = [k for k in MOVED_TO_SIM if k in kwargs]
        if moved:
            raise TypeError(f"Expected the world's settings in sim=SimConfig(...) or sim=MorphoSim(...), found "
                            f"{moved[0]}={kwargs[moved[0]]!r}: the envs take no {' or '.join(MOVED_TO_SIM)} "
                            "argument; pass e.g. sim=SimConfig(reconstruction='oracle', "
                            "generation=GenerationConfig(detail=0.35)) (the default world) instead")
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(kwargs) - set(names))
        if unknown:
            raise TypeError(f"Expected env arguments in {names}, found unknown {unknown}")
        return cls(**{**(defaults or {}), **kwargs})


def env_signature(defaults: Optional[Mapping[str, Any]] = None) -> inspect.Signature:
    """The keyword-only signature of an env's constructor: `EnvConfig`'s fields with the env's
    `defaults` over `EnvConfig`'s."""
    defaults = defaults or {}
    return inspect.Signature([
        inspect.Parameter(f.name, inspect.Parameter.KEYWORD_ONLY, default=defaults.get(f.name, f.default),
                          annotation=f.type)
        for f in fields(EnvConfig)])


def render_backend_of(sim: Any) -> str:
    """The render backend a sim names (`sim.config.render_backend`; "cpu" for a sim without one),
    checked to run here (`BackendUnavailableError` at make, never mid-episode)."""
    from morphosim_gym.errors import BackendUnavailableError
    from morphosim_gym.render.api import BACKENDS, backend_available

    backend = getattr(getattr(sim, "config", None), "render_backend", "cpu")
    if backend not in BACKENDS:
        raise ValueError(f"Expected the sim's render_backend in {BACKENDS}, found {backend!r}")
    if not backend_available(backend):
        raise BackendUnavailableError(f"The sim's render_backend {backend!r} cannot run here (gsplat needs the "
                                      f"gsplat package and a CUDA GPU); use render_backend='cpu'")
    return backend


def make_sim(sim: Any) -> Any:
    """The env's `MorphoSim`: `sim` itself, one built from a `SimConfig`, or from
    `DEFAULT_SIM_CONFIG` for None."""
    if sim is None or isinstance(sim, SimConfig):
        from morphosim_gym.pipeline import MorphoSim

        sim = MorphoSim(DEFAULT_SIM_CONFIG if sim is None else sim)
    config = getattr(sim, "config", None)
    if isinstance(config, SimConfig) and config.reconstruction == "fit":
        from morphosim_gym.reconstruct.presets import resolve_reconstruction_config

        resolve_reconstruction_config(config.reconstruction_config)      # a bad preset name fails at make
    return sim
