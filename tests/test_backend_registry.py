"""Backends by name: the generic registry, the generator and parser registries, and SimConfig's checks
of generator / parser / render backend names (unknown names list the known ones)."""

from __future__ import annotations

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.errors import BackendUnavailableError, UnknownBackendError
from morphosim_gym.generate.backends import GENERATORS, ClipGenerator
from morphosim_gym.language.backends import PARSERS, Parser
from morphosim_gym.registry import Registry, is_factory_spec, load_factory

SMALL = ms.GenerationConfig(width=32, height=32, num_frames=3, detail=0.2, assets="off")


# ---------------------------------------------------------------------------------- custom backends
class RecordingGenerator:
    """A `ClipGenerator` that delegates to the procedural one and records what it was asked."""

    name = "recording"
    calls: list = []

    def __init__(self, config) -> None:
        from morphosim_gym.generate.procedural import ProceduralBackend

        self._inner = ProceduralBackend(config.generation, config.render_backend)

    def generate(self, plan, seed, prompt=None):
        RecordingGenerator.calls.append((plan.text, seed, prompt))
        return self._inner.generate(plan, seed, prompt)


def make_recording(config):
    return RecordingGenerator(config)


class ShoutingParser:
    """A `Parser` that upper-cases the words it hands to the rule parser (and counts calls)."""

    name = "shouting"
    calls = 0

    def __init__(self, llm=None) -> None:
        self.llm = llm

    def parse(self, text, scene=None, *, require_scene=False):
        from morphosim_gym.language.rules import parse_rules

        ShoutingParser.calls += 1
        return parse_rules(text, scene, require_scene)


def make_shouting(llm=None):
    return ShoutingParser(llm)


def make_not_a_generator(config):
    return object()


# ------------------------------------------------------------------------------------- the registry
def test_registry_lists_known_names_and_resolves_factory_specs():
    reg = Registry("widget")
    reg.register("plain", lambda: "made")
    reg.register("lazy", "morphosim_gym.colors:color_rgb")
    assert reg.names() == ("plain", "lazy") and "plain" in reg
    assert reg.create("plain") == "made"
    assert reg.factory("lazy") is load_factory("morphosim_gym.colors:color_rgb")
    with pytest.raises(UnknownBackendError, match=r"Unknown widget 'nope'; known: 'plain', 'lazy', or 'module:factory'"):
        reg.check("nope")
    with pytest.raises(ValueError, match="already registered"):
        reg.register("plain", lambda: None)
    with pytest.raises(ValueError, match="without ':'"):
        reg.register("a:b", lambda: None)
    assert is_factory_spec("pkg.mod:make") and not is_factory_spec("pkg.mod") and not is_factory_spec("a:b:c")


def test_factory_spec_that_fails_to_import_names_the_module():
    with pytest.raises(BackendUnavailableError, match="module 'no_such_module_xyz.gen' .*ModuleNotFoundError"):
        GENERATORS.factory("no_such_module_xyz.gen:make")
    with pytest.raises(UnknownBackendError, match="'morphosim_gym.colors' to define a callable 'no_such_factory'"):
        GENERATORS.factory("morphosim_gym.colors:no_such_factory")


def test_builtin_registries_and_their_protocols():
    assert GENERATORS.names() == ("procedural", "diffusion")
    assert PARSERS.names() == ("rules", "llm", "auto")
    gen = GENERATORS.create("procedural", ms.SimConfig(generation=SMALL))
    assert isinstance(gen, ClipGenerator) and gen.name == "procedural"
    assert isinstance(PARSERS.create("rules"), Parser)
    with pytest.raises(ValueError, match="implement ClipGenerator"):
        GENERATORS.create(f"{__name__}:make_not_a_generator", ms.SimConfig())


# ----------------------------------------------------------------------------------------- SimConfig
@pytest.mark.parametrize("field, value, known", [
    ("generator", "gan", "'procedural', 'diffusion', or 'module:factory'"),
    ("parser", "gpt", "'rules', 'llm', 'auto', or 'module:factory'"),
    ("render_backend", "vulkan", "'cpu', 'torch', 'gsplat'"),
])
def test_unknown_backend_names_list_the_known(field, value, known):
    with pytest.raises(UnknownBackendError) as err:
        ms.SimConfig(**{field: value})
    assert repr(value) in str(err.value) and known in str(err.value)
    with pytest.raises(UnknownBackendError):
        ms.MorphoSim(**{field: value})


def test_render_backend_names_match_the_renderer():
    from morphosim_gym.pipeline import RENDER_BACKENDS
    from morphosim_gym.render import BACKENDS

    assert RENDER_BACKENDS == BACKENDS


def test_module_factory_generator_runs_through_morphosim():
    RecordingGenerator.calls.clear()
    sim = ms.MorphoSim(generator=f"{__name__}:make_recording", generation=SMALL, reconstruction="oracle")
    assert isinstance(sim.generator, RecordingGenerator)
    clip = sim.generate_clip("a red ball rolls to the left", seed=2)
    assert RecordingGenerator.calls == [("a red ball rolls to the left", 2, "a red ball rolls to the left")]
    # the same clip as the procedural generator (it delegates), and oracle works from its ground truth
    ref = ms.MorphoSim(generation=SMALL, reconstruction="oracle").generate_clip("a red ball rolls to the left", seed=2)
    assert np.array_equal(clip.frames, ref.frames)
    scene = sim.generate("a red ball rolls to the left", seed=2)      # no compose(): through its clip
    assert scene.object_names == ref.ground_truth.object_names
    with pytest.raises(BackendUnavailableError, match="'nowhere_pkg'"):
        ms.MorphoSim(generator="nowhere_pkg:make")


def test_module_factory_parser_parses_prompts_and_edits():
    ShoutingParser.calls = 0
    sim = ms.MorphoSim(parser=f"{__name__}:make_shouting", generation=SMALL, reconstruction="oracle")
    scene = sim.generate("a red ball rolls to the left", seed=0)
    assert ShoutingParser.calls == 1
    sim.edit(scene, "make the ball blue")
    assert ShoutingParser.calls == 2 and sim.editor.parser is sim.parser


def test_default_sim_keeps_the_rule_parser_and_the_cpu_renderer():
    sim = ms.MorphoSim()
    assert sim.config.parser == "rules" and sim.parser.name == "rules" and sim.editor.parser is sim.parser
    assert sim.config.render_backend == "cpu" and sim.editor.selector.backend == "cpu"
    assert sim.parse("make the bus blue") == ms.parse("make the bus blue")
