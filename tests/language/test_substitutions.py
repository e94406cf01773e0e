"""Substitutions are never silent: listed, warned, recorded in provenance, refused in strict mode, named
by task instructions."""

import warnings

import pytest

import morphosim_gym as ms
from morphosim_gym.cli import main
from morphosim_gym.language import wordnet
from morphosim_gym.language.substitutions import SubstitutionWarning, describe, plan_substitutions

TINY = ms.GenerationConfig(width=32, height=32, num_frames=2, detail=0.2)


def test_a_noun_outside_the_library_is_a_listed_substitution():
    plan = ms.parse("a kangaroo hops from left to right")
    subs = plan_substitutions(plan)
    kind = "stand-in" if wordnet.available() else "noun"      # WordNet: a thing of the same kind (a mammal)
    assert [(s.kind, s.asked, s.used) for s in subs] == [(kind, "kangaroo", plan.objects[0].category)]
    assert describe(subs[0]).startswith("noun 'kangaroo' is not in the library: using ")
    assert plan_substitutions(ms.parse("a red ball rolls left")) == ()


def test_repaired_misspellings_are_substitutions_of_their_kind():
    subs = plan_substitutions(ms.parse("a bleu ball rols left"))
    assert [(s.kind, s.asked, s.used) for s in subs] == [("colour", "bleu", "blue"), ("motion", "rols", "rolls")]


def test_strict_parse_refuses_what_it_would_substitute():
    with pytest.raises(ms.CommandError, match="strict.*noun 'kangaroo' is not in the library"):
        ms.parse("a kangaroo hops from left to right", strict=True)
    assert ms.parse("a red ball rolls left", strict=True).objects[0].category == "ball"


def test_the_pipeline_warns_records_and_in_strict_mode_refuses():
    sim = ms.MorphoSim(generation=TINY, reconstruction="oracle")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = sim.generate("a kangaroo hops from left to right", seed=0)
    assert any(issubclass(w.category, SubstitutionWarning) and "kangaroo" in str(w.message) for w in caught)
    assert scene.provenance.substitutions[0][:2] == ("kangaroo", scene.objects[1].category)
    strict = ms.MorphoSim(generation=TINY, reconstruction="oracle", strict=True)
    with pytest.raises(ms.CommandError, match="kangaroo"):
        strict.generate("a kangaroo hops from left to right", seed=0)


def test_a_task_instruction_names_what_is_in_the_scene():
    from dataclasses import replace

    from morphosim_gym.scene import Provenance, SceneObject
    from morphosim_gym.tasks import describe_object
    from tests.conftest import make_tiny_scene

    scene = make_tiny_scene(n_per_object=10)
    scene = replace(scene, provenance=Provenance("a kangaroo", 0, "test", substitutions=(("kangaroo", "duck", 0.59),)))
    assert describe_object(SceneObject(1, "kangaroo", "duck"), scene) == "duck"
    assert describe_object(SceneObject(1, "kangaroo", "duck")) == "kangaroo"     # no scene: as written
    assert describe_object(SceneObject(1, "taxi", "car"), scene) == "taxi"   # a library synonym stays as written
    assert describe_object(SceneObject(1, "cylinder", "cylinder"), scene) == "cylinder"


def test_cli_parse_prints_one_note_per_substitution_and_strict_fails(capsys):
    assert main(["parse", "--compact", "a kangaroo hops from left to right"]) == 0
    out, err = capsys.readouterr()
    assert err.count("morphosim parse: note: noun 'kangaroo' is not in the library") == 1
    assert out.startswith("{")                                             # the JSON stays clean
    assert main(["parse", "--strict", "a kangaroo hops from left to right"]) == 2
    assert "strict" in capsys.readouterr().err


def test_cli_generate_prints_the_substitution_and_strict_fails(tmp_path, capsys):
    args = ["generate", "a kangaroo hops from left to right", "--size", "32", "--frames", "2", "--format", "gif"]
    assert main(args + ["--out", str(tmp_path / "a")]) == 0
    assert "morphosim generate: note: noun 'kangaroo' is not in the library" in capsys.readouterr().err
    assert main(args + ["--out", str(tmp_path / "b"), "--strict"]) == 2
    assert not (tmp_path / "b").exists()


def test_grounding_exact_is_the_one_setting_strict_is_its_old_spelling(capsys):
    for kwargs in ({"grounding": "exact"}, {"strict": True}):
        with pytest.raises(ms.CommandError, match="exact.*noun 'kangaroo' is not in the library"):
            ms.parse("a kangaroo hops from left to right", **kwargs)
        sim = ms.MorphoSim(generation=TINY, reconstruction="oracle", **kwargs)
        with pytest.raises(ms.CommandError, match="kangaroo"):
            sim.generate("a kangaroo hops from left to right", seed=0)
    with pytest.raises(ValueError, match="grounding"):
        ms.SimConfig(grounding="sloppy")
    assert main(["parse", "--grounding", "exact", "a kangaroo hops from left to right"]) == 2
    assert "exact" in capsys.readouterr().err
    assert main(["parse", "--compact", "--grounding", "nearest", "a red ball rolls left"]) == 0
