"""`MorphoSim`: the pipeline of the paper — parse, route, generate, reconstruct, edit — with a cache.

    sim = MorphoSim()                                   # offline CPU defaults
    clip = sim.generate_clip("a red ball bounces from right to left", seed=0)
    scene = sim.generate("a red ball bounces from right to left", seed=0)
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Optional

from .errors import CommandError
from .generate.compose import GenerationConfig
from .generate.version import GENERATOR_VERSION
from .scene import GeneratedClip, Scene4D, load_clip, load_scene, save_clip, save_scene
from .scene.diskcache import load_or_build

__all__ = ["MorphoSim", "SimConfig", "RECONSTRUCTIONS", "default_cache_dir"]

RECONSTRUCTIONS = ("fit", "oracle")


def default_cache_dir() -> Path:
    """`$MORPHOSIM_CACHE`, else `~/.cache/morphosim_gym`."""
    return Path(os.environ.get("MORPHOSIM_CACHE", Path.home() / ".cache" / "morphosim_gym"))


@dataclass(frozen=True)
class SimConfig:
    """Pipeline configuration.

    Attributes:
        generator: clip backend, "procedural" (offline default).
        reconstruction: how a clip becomes a Scene4D: "fit" (default) reconstructs dynamic
            Gaussians, a motion scaffold and a feature field from the clip alone (about two
            minutes on a laptop CPU, cached on disk); "oracle" uses the generator's ground truth
            directly, a fast path for training at scale (no feature field: edits select objects
            by their ids).
        reconstruction_config: settings of the "fit" reconstruction: a `ReconstructionConfig`, a
            preset name ("fast", "full"; `reconstruct.presets`) or None ("full").
        generation: clip size, length and detail.
        render_backend: renderer used for frames ("cpu").
        cache: cache on disk by content hash: generated clips, and with `reconstruction="oracle"`
            the composed scenes `generate` returns (`.msim` files under `cache_dir/scene/`).
        cache_dir: where; None = `default_cache_dir()`.
    """

    generator: str = "procedural"
    reconstruction: str = "fit"
    reconstruction_config: Any = None
    generation: GenerationConfig = field(default_factory=GenerationConfig)
    render_backend: str = "cpu"
    cache: bool = False
    cache_dir: Optional[str] = None

    def __post_init__(self) -> None:
        if self.generator != "procedural":
            raise ValueError(f"Expected generator 'procedural', found {self.generator!r}")
        if self.reconstruction not in RECONSTRUCTIONS:
            raise ValueError(f"Expected reconstruction in {RECONSTRUCTIONS}, found {self.reconstruction!r}")


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
        from .generate.procedural import ProceduralBackend

        self._generator = ProceduralBackend(self.config.generation, self.config.render_backend)
        self.editor = SceneEditor(Selector(backend=self.config.render_backend))

    # -------------------------------------------------------------- parsing
    def parse(self, text: str, scene: Scene4D | None = None) -> Any:
        """The plan of a command (see `morphosim_gym.parse`)."""
        from .language import parse

        return parse(text, scene=scene)

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
            scene = self._cached_oracle_scene(plan, prompt, seed) if self.config.cache else \
                self._generator.compose(plan, seed, prompt).scene
        else:
            scene = self.reconstruct(self.generate_clip(prompt, seed))
        for follow in plan.then:
            scene = self.edit(scene, follow.text)
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
        key = json.dumps({"prompt": prompt, "seed": seed, "generation": asdict(self.config.generation),
                          "generator": self.config.generator, "version": GENERATOR_VERSION}, sort_keys=True)
        digest = hashlib.sha256(key.encode()).hexdigest()[:24]
        return root / kind / f"{digest}{suffix}"

    def __repr__(self) -> str:
        c = self.config
        return f"MorphoSim(generator={c.generator!r}, reconstruction={c.reconstruction!r})"
