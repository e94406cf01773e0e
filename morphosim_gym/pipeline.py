"""`MorphoSim`: the pipeline of the paper — parse, route, generate, reconstruct, edit — with a cache.

    sim = MorphoSim()                                   # offline CPU defaults
    clip = sim.generate_clip("a red ball bounces from right to left", seed=0)
    scene = sim.generate("a red ball bounces from right to left", seed=0)
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Optional

from .errors import CommandError, UnknownBackendError
from .generate.backends import GENERATORS
from .generate.compose import GenerationConfig
from .language.backends import PARSERS
from .generate.version import GENERATOR_VERSION
from .scene import GeneratedClip, Scene4D, load_clip, load_scene, save_clip, save_scene
from .scene.diskcache import load_or_build

if TYPE_CHECKING:      # imported when used: the diffusion settings import torch
    from .generate.diffusion.backend import DiffusionConfig
    from .language.llm import LLMConfig

__all__ = ["MorphoSim", "SimConfig", "RECONSTRUCTIONS", "default_cache_dir"]

RECONSTRUCTIONS = ("fit", "oracle")
RENDER_BACKENDS = ("cpu", "torch", "gsplat")      # `render.api.BACKENDS` (checked equal by the tests)


def default_cache_dir() -> Path:
    """`$MORPHOSIM_CACHE`, else `~/.cache/morphosim_gym`."""
    return Path(os.environ.get("MORPHOSIM_CACHE", Path.home() / ".cache" / "morphosim_gym"))


@dataclass(frozen=True)
class SimConfig:
    """Pipeline configuration.

    Attributes:
        generator: clip backend (`generate.backends.GENERATORS`): "procedural" (offline default),
            "diffusion" (CogVideoX with trajectory attention guidance on the planner's boxes; needs
            `diffusion` with local weights and ``reconstruction="fit"``), or "module:factory" (imports
            `module`, calls `factory(config)`; runs that code).
        reconstruction: how a clip becomes a Scene4D: "fit" (default) reconstructs dynamic
            Gaussians, a motion scaffold and a feature field from the clip alone (about two
            minutes on a laptop CPU, cached on disk); "oracle" uses the generator's ground truth
            directly, a fast path for training at scale (no feature field: edits select objects
            by their ids).
        reconstruction_config: settings of the "fit" reconstruction: a `ReconstructionConfig`, a
            preset name ("fast", "full"; `reconstruct.presets`) or None ("full").
        generation: clip size, length and detail.
        render_backend: renderer used for frames, selections and the envs' observations: "cpu"
            (default), "torch" (reference) or "gsplat" (CUDA).
        diffusion: settings of the "diffusion" generator (`DiffusionConfig`, or a mapping of its keys:
            weights_path, device, steps, guidance...); None = its defaults (which name no weights).
        parser: what parses prompts and edits (`language.backends.PARSERS`): "rules" (offline
            default), "llm" (an OpenAI-compatible endpoint, `llm`), "auto" ("llm" when `llm` names an
            endpoint and a model, else "rules"), or "module:factory" (called with `llm`).
        llm: the endpoint of the "llm" / "auto" parsers (`LLMConfig`, or a mapping of its keys); None =
            the MORPHOSIM_LLM_* environment.
        cache: cache on disk by content hash: generated clips, and with `reconstruction="oracle"`
            the composed scenes `generate` returns (`.msim` files under `cache_dir/scene/`).
        cache_dir: where; None = `default_cache_dir()`.
        grounding: the grounding level of every parse of the pipeline (generate, generate_clip, env
            scenes), one of `language.grounding.LEVELS`; None = `$MORPHOSIM_GROUNDING`, else "kind".
            "exact" raises `CommandError` instead of substituting anything ("kangaroo" -> a
            stand-in, see `morphosim_gym.language.substitutions`); under the other levels each
            substitution is a `SubstitutionWarning` and is recorded in the scene's provenance.
        strict: deprecated alias of ``grounding="exact"``.
    """

    generator: str = "procedural"
    reconstruction: str = "fit"
    reconstruction_config: Any = None
    generation: GenerationConfig = field(default_factory=GenerationConfig)
    render_backend: str = "cpu"
    cache: bool = False
    cache_dir: Optional[str] = None
    strict: bool = False
    grounding: Optional[str] = None
    diffusion: Optional["DiffusionConfig"] = None
    parser: str = "rules"
    llm: Optional["LLMConfig"] = None

    def __post_init__(self) -> None:
        GENERATORS.check(self.generator)
        PARSERS.check(self.parser)
        if self.grounding is not None:
            from .language.grounding import grounding_level

            object.__setattr__(self, "grounding", grounding_level(self.grounding))
        if self.render_backend not in RENDER_BACKENDS:
            raise UnknownBackendError(f"Unknown render backend {self.render_backend!r}; known: "
                                      f"{', '.join(repr(b) for b in RENDER_BACKENDS)}")
        if self.reconstruction not in RECONSTRUCTIONS:
            raise ValueError(f"Expected reconstruction in {RECONSTRUCTIONS}, found {self.reconstruction!r}")
        if self.diffusion is not None:
            from .generate.diffusion.backend import DiffusionConfig

            if isinstance(self.diffusion, Mapping):        # e.g. a YAML section
                object.__setattr__(self, "diffusion", DiffusionConfig.from_dict(self.diffusion))
            if not isinstance(self.diffusion, DiffusionConfig):
                raise ValueError(f"Expected diffusion as a DiffusionConfig or None, found "
                                 f"{type(self.diffusion).__name__}")
        if self.llm is not None:
            from .language.llm import LLMConfig

            if isinstance(self.llm, Mapping):
                object.__setattr__(self, "llm", LLMConfig.from_dict(self.llm))
            if not isinstance(self.llm, LLMConfig):
                raise ValueError(f"Expected llm as an LLMConfig or None, found {type(self.llm).__name__}")


class MorphoSim:
    """Language in, editable 4D scenes out.

    Args:
        config: a `SimConfig`, or None for the defaults; keyword arguments override its fields
            (e.g. `MorphoSim(reconstruction="oracle")`).
    """

    def __init__(self, config: SimConfig | None = None, **overrides: Any) -> None:
        config = config or SimConfig()
        if "generation" in overrides and isinstance(overrides["generation"], dict):
            overrides["generation"] = GenerationConfig(**overrides["generation"])
        unknown = set(overrides) - {f for f in asdict(config)}
        if unknown:
            raise ValueError(f"Expected SimConfig fields, found unknown {sorted(unknown)}; "
                             f"known: {sorted(asdict(config))}")
        self.config = replace(config, **overrides)
        from .edit import SceneEditor, Selector

        c = self.config
        self._generator = GENERATORS.create(c.generator, c)
        if c.reconstruction == "oracle" and getattr(self._generator, "ground_truth", True) is False:
            raise ValueError(f"Expected reconstruction='fit' with generator {c.generator!r}: its clips carry no "
                             f"ground truth for reconstruction='oracle'")
        self.parser = PARSERS.create(c.parser, c.llm)
        self.editor = SceneEditor(Selector(backend=c.render_backend), parser=self.parser)

    @property
    def generator(self) -> Any:
        """The clip generator `SimConfig.generator` names (a `generate.backends.ClipGenerator`)."""
        return self._generator

    # -------------------------------------------------------------- parsing
    def parse(self, text: str, scene: Scene4D | None = None) -> Any:
        """The plan of a command (see `morphosim_gym.parse`), by the parser `SimConfig.parser` names
        (the one edits use too), at the grounding level `SimConfig.grounding`: "exact" makes a
        substitution a `CommandError`, the other levels a `SubstitutionWarning`."""
        from .language.grounding import using_level
        from .language.substitutions import check_strict, warn

        with using_level("exact" if self.config.strict else self.config.grounding) as level:
            plan = self.parser.parse(text, scene)
        if level == "exact":
            check_strict(plan)
        warn(plan)
        return plan

    # ----------------------------------------------------------- generation
    def generate_clip(self, prompt: str, seed: int = 0) -> GeneratedClip:
        """Generate a clip of a generate command; `CommandError` for an edit command or bad text."""
        plan = self.parse(prompt)
        if plan.mode != "generate":
            raise CommandError(f"Expected a command that describes a scene to generate, found an edit command "
                               f"({prompt!r}); use sim.edit(scene, text) for edits")
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ValueError(f"Expected seed as a non-negative integer, found {seed!r}")
        if not self.config.cache:
            return self._generator.generate(plan, seed, prompt)
        return load_or_build(self._cache_path("clip", prompt, seed), load_clip,
                             lambda: self._generator.generate(plan, seed, prompt), save_clip)

    def reconstruct(self, clip: GeneratedClip) -> Scene4D:
        """The 4D scene of a clip: fitted to it (default), or with `reconstruction="oracle"` its ground truth."""
        if not isinstance(clip, GeneratedClip):
            raise ValueError(f"Expected a GeneratedClip, found {type(clip).__name__}")
        if self.config.reconstruction == "fit":
            from dataclasses import replace as _replace

            from .reconstruct import reconstruct
            from .reconstruct.presets import resolve_reconstruction_config

            cfg = resolve_reconstruction_config(self.config.reconstruction_config)
            if self.config.cache_dir and cfg.cache_dir is None:
                cfg = _replace(cfg, cache_dir=str(Path(self.config.cache_dir) / "reconstruct"))
            return reconstruct(clip, cfg)
        if self.config.reconstruction == "oracle":
            if clip.ground_truth is None:
                raise ValueError("Expected a clip with a ground truth for reconstruction='oracle', found none "
                                 "(clips from the diffusion backend need real reconstruction)")
            return clip.ground_truth
        raise ValueError(f"Expected reconstruction in {RECONSTRUCTIONS}, found {self.config.reconstruction!r}")

    def generate(self, prompt: str, seed: int = 0) -> Scene4D:
        """Generate and reconstruct: a sentence to an editable Scene4D. Follow-up edits of a
        compound command ("...; then make the cube blue") are applied in order. With
        `reconstruction="oracle"` the generator's ground truth is composed directly (the same
        scene as `generate_clip(...).ground_truth`, without rendering the clip's frames)."""
        plan = self.parse(prompt)
        if self.config.reconstruction == "oracle":
            # the ground truth is all the oracle path keeps: compose it without rendering the clip
            if plan.mode != "generate":
                raise CommandError(f"Expected a command that describes a scene to generate, found an edit command "
                                   f"({prompt!r}); use sim.edit(scene, text) for edits")
            if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
                raise ValueError(f"Expected seed as a non-negative integer, found {seed!r}")
            if not hasattr(self._generator, "compose"):      # a generator whose clips carry the ground truth
                scene = self.reconstruct(self.generate_clip(prompt, seed))
            elif self.config.cache:
                scene = self._cached_oracle_scene(plan, prompt, seed)
            else:
                scene = self._generator.compose(plan, seed, prompt).scene
        else:
            scene = self.reconstruct(self.generate_clip(prompt, seed))
        return self.apply_follow_ups(scene, plan)

    def apply_follow_ups(self, scene: Scene4D, plan: Any) -> Scene4D:
        """Apply a generate plan's follow-up edits to its generated scene, in order. Follow-ups that
        continue a motion ("then stops") are second stages the generator already played, not edits
        (see `morphosim_gym.language.sequence`)."""
        from .language.sequence import follow_up_edits

        for text in follow_up_edits(plan):
            scene = self.edit(scene, text)
        return scene

    # --------------------------------------------------------------- edits
    def edit(self, scene: Scene4D, text: str) -> Scene4D:
        """Apply a language edit to a scene without re-generating it: a new scene whose `undo()` is
        `scene` (see `morphosim_gym.edit.SceneEditor`)."""
        return self.editor.edit(scene, text)

    # ---------------------------------------------------------------- cache
    def _cached_oracle_scene(self, plan: Any, prompt: str, seed: int) -> Scene4D:
        """The composed ground truth of a prompt, through the on-disk cache: parallel workers (a
        benchmark sweep) generate each scene once and load it bit-exact (writes are atomic; a damaged
        entry is composed again and replaced, with a warning)."""
        return load_or_build(self._cache_path("scene", prompt, seed, ".msim"), load_scene,
                             lambda: self._generator.compose(plan, seed, prompt).scene,
                             lambda scene, path: save_scene(scene, path, history=False))

    def _cache_path(self, kind: str, prompt: str, seed: int, suffix: str = ".mclip") -> Path:
        """Where a clip or scene is cached: a hash of what decides it, the generator's version included."""
        root = Path(self.config.cache_dir) if self.config.cache_dir else default_cache_dir()
        fields = {"prompt": prompt, "seed": seed, "generation": asdict(self.config.generation),
                  "generator": self.config.generator, "version": GENERATOR_VERSION}
        settings = getattr(self._generator, "cache_settings", None)
        if settings is not None:                      # e.g. the diffusion model's weights and steps
            fields["generator_settings"] = settings()
        key = json.dumps(fields, sort_keys=True, default=str)
        digest = hashlib.sha256(key.encode()).hexdigest()[:24]
        return root / kind / f"{digest}{suffix}"

    def __repr__(self) -> str:
        c = self.config
        return f"MorphoSim(generator={c.generator!r}, reconstruction={c.reconstruction!r}, parser={c.parser!r})"
