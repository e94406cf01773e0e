"""`morphosim bench --strict`: a substituted noun in a suite's prompt fails its episodes with the CommandError."""

import json

from morphosim_gym.cli import main

from .conftest import write_suite


def _suite(tmp_path, noun: str):
    return write_suite(tmp_path / f"{noun}.yaml", {
        "name": f"strict_{noun}", "env": "MorphoSim/Track-v0", "env_kwargs": {"width": 32, "height": 32},
        "episodes": 1, "frames": 0,
        "scenes": {"prompt": "a red {object} moves from left to right", "fields": {"object": [noun]},
                   "target": "object", "target_color": None},
        "perturbations": [{"name": "recolor", "edits": "make the {target} blue"}]})


def _records(out) -> list[dict]:
    return [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines() if line.strip()]


def test_strict_records_a_substituted_noun_as_a_per_episode_command_error(tmp_path, cache_dir):
    out = tmp_path / "out"
    argv = ["bench", str(_suite(tmp_path, "kangaroo")), "--out", str(out), "--cache-dir", cache_dir,
            "--no-progress", "--strict"]
    code = main(argv)
    records = _records(out)
    assert code == len(records) == 2
    for r in records:
        assert r["status"] == "failed" and r["error_stage"] == "scene"
        assert r["error"].startswith("CommandError: ") and "kangaroo" in r["error"] and "strict" in r["error"]
    # resuming the same folder without --strict is refused (its records were made under other settings)
    assert main(argv[:-1]) == 255


def test_strict_runs_a_suite_without_substitutions(tmp_path, cache_dir):
    out = tmp_path / "out"
    code = main(["bench", str(_suite(tmp_path, "ball")), "--out", str(out), "--cache-dir", cache_dir,
                 "--no-progress", "--strict"])
    assert code == 0 and all(r["status"] == "ok" for r in _records(out))
