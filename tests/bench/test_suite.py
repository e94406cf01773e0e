"""Suite files: the shipped suites load; bad keys are errors that name the key and the file."""

import pytest

from morphosim_gym.bench import SuiteError, builtin_suite_names, load_suite
from morphosim_gym.bench.perturb import resolve_edits, sample_episode, template_values
from morphosim_gym.bench.suite import ENV_TASKS, Perturbation

from .conftest import write_suite

SMOKE = {"name": "tiny", "env": "MorphoSim/Track-v0", "episodes": 2,
         "perturbations": [{"name": "blue", "edits": "make the {target} blue"}]}


def test_shipped_suites_cover_every_env_and_load():
    names = builtin_suite_names()
    assert {"smoke", "track", "reach", "find"} <= set(names)
    envs = set()
    for name in names:
        suite = load_suite(name)
        envs.add(suite.env_id)
        assert suite.perturbations and all(p.error is None for p in suite.perturbations), name
        assert suite.conditions[0].name == "base"
    assert envs == set(ENV_TASKS)


def test_unknown_top_level_key_names_key_and_file(tmp_path):
    path = write_suite(tmp_path / "typo.yaml", dict(SMOKE, episods=3))
    with pytest.raises(SuiteError) as err:
        load_suite(str(path))
    assert "'episods'" in str(err.value) and str(path) in str(err.value)


@pytest.mark.parametrize("entry, words", [
    ({"name": "a", "edit": "make the {target} red"}, ["'edit'", "perturbations[0]"]),
    ({"name": "b", "edits": "make the {targte} red"}, ["{targte}"]),
    ({"name": "c", "camera": {"yaw": 10}}, ["'yaw'", "camera"]),
    ({"name": "d"}, ["'edits' or 'camera'"]),
    ({"name": "e", "edits": "make the {target} red", "at": -1}, ["'at'"]),
])
def test_bad_perturbation_is_kept_with_its_error(tmp_path, entry, words):
    path = write_suite(tmp_path / "bad.yaml", dict(SMOKE, perturbations=[entry, SMOKE["perturbations"][0]]))
    suite = load_suite(str(path))
    bad, good = suite.perturbations
    assert good.error is None
    assert bad.error is not None and str(path) in bad.error
    for w in words:
        assert w in bad.error


def test_other_bad_suites(tmp_path):
    for data, word in [(dict(SMOKE, env="MorphoSim/Fly-v0"), "'env'"),
                       (dict(SMOKE, env_kwargs={"sim": 1}), "'sim'"),
                       (dict(SMOKE, episodes=0), "'episodes'"),
                       (dict(SMOKE, perturbations=[SMOKE["perturbations"][0]] * 2), "twice"),
                       (dict(SMOKE, scenes={"prompt": "a {color} ball", "fields": {"colour": ["red"]}}), "scenes")]:
        with pytest.raises(SuiteError, match=word):
            load_suite(str(write_suite(tmp_path / "s.yaml", data)))
    with pytest.raises(SuiteError, match="built-in suite"):
        load_suite("no_such_suite")


def test_episodes_are_drawn_from_the_seed_alone():
    suite = load_suite("track")
    a, b = sample_episode(suite, 5), sample_episode(suite, 5)
    assert a == b and a != sample_episode(suite, 6)
    assert "next to" in a.request.prompt                      # the suite's own scene distribution


def test_templates_fill_from_the_scene(cache_dir):
    import morphosim_gym as ms
    from morphosim_gym.tasks import make_task

    suite = load_suite("find")
    ep = sample_episode(suite, 0)
    scene = ms.MorphoSim(reconstruction="oracle").generate(ep.request.prompt, seed=ep.scene_seed)
    values = template_values(scene, make_task(suite.task), ep.request)
    assert values["target"] == ep.request.target_description
    assert values["distractor"] and values["distractor"] != values["target"]
    colours = {v.split()[0] for v in (values["target"], values["distractor"])}
    assert values["new_color"] not in colours
    edits = resolve_edits(Perturbation("x", ("make the {distractor} {target_color}",)), values)
    assert edits == (f"make the {values['distractor']} {values['target_color']}",)
