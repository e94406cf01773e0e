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


def test_the_level_is_carried_to_pool_workers_not_through_the_environment(tmp_path, cache_dir, monkeypatch):
    """`run_sweep(grounding=...)` hands the level itself to every worker: two pool workers refuse the
    stand-in while this process's own level (the environment's) would accept it, and the
    environment is left as it was."""
    from morphosim_gym.bench.runner import run_sweep
    from morphosim_gym.bench.suite import load_suite
    from morphosim_gym.language.grounding import LEVEL_VAR

    monkeypatch.setenv(LEVEL_VAR, "kind")
    result = run_sweep(load_suite(str(_suite(tmp_path, "kangaroo"))), ["oracle"], tmp_path / "out", workers=2,
                       cache_dir=cache_dir, progress=False, report=False, grounding="exact")
    records = _records(tmp_path / "out")
    assert result.failed == len(records) == 2
    assert all(r["error_stage"] == "scene" and r["error"].startswith("CommandError: ") for r in records)
    assert json.loads((tmp_path / "out" / "manifest.json").read_text())["grounding"] == "exact"
    import os

    assert os.environ[LEVEL_VAR] == "kind"


def test_bench_grounding_flag_is_recorded_and_a_resume_under_another_level_is_refused(tmp_path, cache_dir):
    import os

    from morphosim_gym.language.grounding import LEVEL_VAR

    before = os.environ.get(LEVEL_VAR)
    out = tmp_path / "out"
    argv = ["bench", str(_suite(tmp_path, "ball")), "--out", str(out), "--cache-dir", cache_dir, "--no-progress"]
    assert main(argv + ["--grounding", "checked"]) == 0
    assert os.environ.get(LEVEL_VAR) == before                  # the flag does not leak into the environment
    assert json.loads((out / "manifest.json").read_text())["grounding"] == "checked"
    assert main(argv + ["--grounding", "checked"]) == 0          # same level: resumes
    assert main(argv + ["--grounding", "nearest"]) == 255        # another level: refused
