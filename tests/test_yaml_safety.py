"""The config YAML loader of task specs and suites: alias bombs, duplicate keys, wrong types and
damaged files are clean `ValueError`s naming the file (and the key), in milliseconds."""

import copy
import time
from pathlib import Path

import pytest
import yaml
from morphosim_gym.tasks import TASK_DIR, load_task_spec

from morphosim_gym.bench.suite import SuiteError, load_suite
from morphosim_gym.config_yaml import ConfigError, load_yaml_file, load_yaml_text

SHIPPED = sorted(TASK_DIR.glob("*.yaml")) + sorted((TASK_DIR / "suites").glob("*.yaml"))


def _laughs(levels: int, width: int) -> str:
    """The "billion laughs" document: each level an anchored list of `width` aliases of the one below."""
    text = "lol0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
    for i in range(1, levels + 1):
        text += f"lol{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * width) + "]\n"
    return text


def _suite_with(tmp_path, extra: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text("name: s\nenv: MorphoSim/Track-v0\nperturbations: []\n" + extra)
    return path


def test_shipped_files_load_as_with_safe_load():
    for f in SHIPPED:
        assert load_yaml_file(f) == yaml.safe_load(f.read_text()), f


@pytest.mark.parametrize("levels, width", [(9, 9), (5, 10)])
def test_billion_laughs_suite_is_refused_fast(tmp_path, levels, width):
    """9 x 9 aliases: 648 bytes that used to expand for > 90 s; 5 x 10: few aliases, 10^5 nodes."""
    path = _suite_with(tmp_path, "description: x\nlaughs:\n" + "".join(
        f"  {line}\n" for line in _laughs(levels, width).splitlines()))
    start = time.perf_counter()
    with pytest.raises(SuiteError, match=r"s\.yaml: line \d+: .*(aliases|expands)"):
        load_suite(path)
    assert time.perf_counter() - start < 2.0


def test_recursive_alias_and_deep_nesting(tmp_path):
    with pytest.raises(ConfigError, match="t.yaml"):
        load_yaml_text("a: &x [1, *x]\n", "t.yaml")
    with pytest.raises(ConfigError, match="nested too deeply|not valid YAML"):
        load_yaml_text("a: " + "[" * 20000 + "]" * 20000, "t.yaml")


def test_a_few_aliases_still_work():
    assert load_yaml_text("base: &b {x: 1}\nother: *b\n", "t.yaml") == {"base": {"x": 1}, "other": {"x": 1}}


def test_duplicate_keys_are_refused(tmp_path):
    path = _suite_with(tmp_path, "episodes: 3\nepisodes: 30\n")
    with pytest.raises(SuiteError, match=r"s\.yaml: line 5: duplicate key 'episodes' \(first on line 4\)"):
        load_suite(path)
    task = tmp_path / "t.yaml"
    task.write_text((TASK_DIR / "track.yaml").read_text() + "params: {success_fraction: 0.5}\n")
    with pytest.raises(ValueError, match=r"t\.yaml: line \d+: duplicate key 'params'"):
        load_task_spec(task)


def test_wrong_types_are_value_errors_naming_file_and_key(tmp_path):
    base = yaml.safe_load((TASK_DIR / "find.yaml").read_text())
    cases = [(("scenes", "target_color"), [1], "scenes.target_color", "a string"),
             (("scenes", "distractors", "count"), 3, "scenes.distractors.count", "a list"),
             (("scenes", "distractors", "count"), [1, None], r"scenes.distractors.count\[1\]", "an integer"),
             (("scenes", "distractors", "objects"), None, "scenes.distractors.objects", "a list"),
             (("params",), {"foo": "abc"}, "params.foo", "a number")]
    for keys, value, key, what in cases:
        d = copy.deepcopy(base)
        parent = d
        for k in keys[:-1]:
            parent = parent[k]
        parent[keys[-1]] = value
        path = tmp_path / "x.yaml"
        path.write_text(yaml.safe_dump(d))
        with pytest.raises(ValueError, match=rf"x\.yaml: key '{key}': expected {what}, found") as info:
            load_task_spec(path)
        assert not isinstance(info.value, TypeError)
    suite = tmp_path / "e.yaml"
    suite.write_text("name: s\nenv: [1]\nperturbations: []\n")      # used to be a raw TypeError (unhashable)
    with pytest.raises(SuiteError, match=r"'env'.*e\.yaml"):
        load_suite(suite)


def test_task_errors_name_the_file(tmp_path):
    path = tmp_path / "k.yaml"
    d = yaml.safe_load((TASK_DIR / "track.yaml").read_text())
    d["kind"] = "juggle"
    path.write_text(yaml.safe_dump(d))
    with pytest.raises(ValueError, match=rf"^{path}: Expected kind"):
        load_task_spec(path)


def test_unreadable_and_binary_files(tmp_path):
    path = tmp_path / "b.yaml"
    path.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(ConfigError, match=r"b\.yaml: not UTF-8"):
        load_yaml_file(path)
    big = tmp_path / "big.yaml"
    big.write_bytes(b"#" * (2 << 20))
    with pytest.raises(ConfigError, match="more than a configuration file needs"):
        load_yaml_file(big)
