"""Sweeps end to end: outputs, pairing, both backends identical, bad input reported per episode."""

import csv
import json

import pytest

from morphosim_gym.bench import load_suite, run_sweep
from morphosim_gym.bench.suite import BASE
from morphosim_gym.cli import main

from .conftest import REPO, strip_timing, write_suite


@pytest.fixture(scope="module")
def smoke_local(tmp_path_factory, cache_dir):
    out = tmp_path_factory.mktemp("smoke_local")
    return run_sweep(load_suite("smoke"), ["oracle", "random"], out, cache_dir=cache_dir, progress=False)


def test_smoke_outputs_and_pairing(smoke_local):
    result = smoke_local
    suite = load_suite("smoke")
    n = 2 * len(suite.conditions) * suite.episodes
    assert len(result.records) == n and result.failed == 0
    for name in ("results.json", "results.csv", "report.md", "success.png", "frames_oracle.png", "frames_random.png"):
        assert (result.out / name).stat().st_size > 0, name
    data = json.loads((result.out / "results.json").read_text())
    assert len(data["episodes"]) == n and data["suite"]["digest"] == suite.digest()
    with open(result.out / "results.csv") as fh:
        assert len(list(csv.DictReader(fh))) == n
    by = {(r["policy"], r["perturbation"], r["seed"]): r for r in result.records}
    for (policy, pert, seed), r in by.items():
        base = by[(policy, BASE, seed)]
        assert (r["prompt"], r["scene_seed"], r["target"]) == (base["prompt"], base["scene_seed"], base["target"])
    recolor = by[("oracle", "recolor_target", 0)]
    assert recolor["edits"] and recolor["edits"][0].startswith(f"make the {recolor['target']} ")
    assert by[("oracle", "camera_shift", 0)]["camera"]["position"]
    report = (result.out / "report.md").read_text()
    assert "Δ return vs base [95% CI]" in report and "| reverse_target |" in report


@pytest.mark.slow
def test_ray_backend_gives_identical_results(smoke_local, tmp_path, cache_dir):
    local = smoke_local
    ray_result = run_sweep(load_suite("smoke"), ["oracle", "random"], tmp_path / "ray", backend="ray", workers=2,
                           cache_dir=cache_dir, progress=False)
    assert strip_timing(ray_result.records) == strip_timing(local.records)


def test_process_pool_gives_identical_results(smoke_local, tmp_path, cache_dir):
    local = smoke_local
    suite = load_suite("smoke").with_episodes(2)
    pool = run_sweep(suite, ["oracle", "random"], tmp_path / "pool", workers=2, cache_dir=cache_dir,
                     progress=False, report=False)
    wanted = [r for r in local.records if r["seed"] < 2]
    assert strip_timing(pool.records) == strip_timing(wanted)


def test_bad_input_is_recorded_per_episode_and_counted_in_the_exit_status(tmp_path, cache_dir, monkeypatch):
    monkeypatch.syspath_prepend(str(REPO))
    suite = write_suite(tmp_path / "bad.yaml", {
        "name": "bad", "env": "MorphoSim/Track-v0", "env_kwargs": {"width": 32, "height": 32}, "episodes": 2,
        "frames": 0,
        "scenes": {"prompt": "a red {object} moves from left to right", "fields": {"object": ["ball"]},
                   "target": "object", "target_color": None},
        "perturbations": [
            {"name": "fine", "edits": "make the {target} blue"},
            {"name": "typo_key", "edits": "make the {target} blue", "when": 3},
            {"name": "no_giraffe", "edits": "make the giraffe blue"},
            {"name": "no_distractor", "edits": "delete the {distractor}"},
            {"name": "late_failure", "edits": "make the giraffe blue", "at": 5},
        ]})
    out = tmp_path / "out"
    policies = ["oracle", "tests.bench.policies:raises_at_step_3", "tests.bench.policies:wrong_shape",
                "tests.bench.policies:nan_action", "tests.bench.policies:factory_raises"]
    argv = ["bench", str(suite), "--out", str(out), "--cache-dir", cache_dir, "--no-progress"]
    for p in policies:
        argv += ["--policy", p]
    code = main(argv)
    records = json.loads((out / "results.json").read_text())["episodes"]
    failed = [r for r in records if r["status"] != "ok"]
    assert code == len(failed) > 0
    by = {(r["policy"], r["perturbation"], r["seed"]): r for r in records}
    ok = by[("oracle", "fine", 0)]
    assert ok["status"] == "ok" and ok["success"] is not None
    expect = {("oracle", "typo_key"): ("suite", "'when'"), ("oracle", "no_giraffe"): ("perturbation", "giraffe"),
              ("oracle", "no_distractor"): ("perturbation", "{distractor}"),
              ("oracle", "late_failure"): ("perturbation", "before step 5"),
              ("tests.bench.policies:raises_at_step_3", BASE): ("policy", "policy exploded"),
              ("tests.bench.policies:wrong_shape", BASE): ("policy", "expected shape (3,)"),
              ("tests.bench.policies:nan_action", BASE): ("policy", "finite"),
              ("tests.bench.policies:factory_raises", BASE): ("policy", "no checkpoint")}
    for (policy, pert), (stage, text) in expect.items():
        for seed in (0, 1):
            r = by[(policy, pert, seed)]
            assert r["status"] == "failed" and r["error_stage"] == stage and text in r["error"], r
    assert "typo_key" in (out / "report.md").read_text()
    assert by[("oracle", "late_failure", 0)]["steps"] == 0      # the record says nothing ran past the failure


def test_list_shows_the_shipped_suites(capsys):
    assert main(["bench", "--list"]) == 0
    listed = capsys.readouterr().out
    for name in ("smoke", "track", "reach", "find"):
        assert name in listed


def test_sweep_level_errors_exit_255(tmp_path, capsys):
    assert main(["bench", "no_such_suite", "--out", str(tmp_path / "x")]) == 255
    assert "no_such_suite" in capsys.readouterr().err
    assert main(["bench", "smoke", "--policy", "nope", "--out", str(tmp_path / "y")]) == 255
    bad_kwargs = write_suite(tmp_path / "w.yaml", {"name": "w", "env": "MorphoSim/Track-v0", "env_kwargs": {"width": 3},
                                                   "perturbations": [{"name": "p", "edits": "make the {target} red"}]})
    assert main(["bench", str(bad_kwargs), "--out", str(tmp_path / "z")]) == 255
    err = capsys.readouterr().err
    assert "env_kwargs" in err and "width" in err and str(bad_kwargs) in err
    assert not (tmp_path / "z" / "results.jsonl").exists()


def test_frames_of_an_episode_that_ends_early_show_its_end(cache_dir):
    from morphosim_gym.bench import EpisodeKey, EpisodeRunner

    res = EpisodeRunner(load_suite("find"), cache_dir).run(EpisodeKey("oracle", "narrow_camera", 0), frames=5)
    assert res.record["terminated"] and res.record["steps"] < 30
    f = res.frames
    assert f.shape[0] == 5 and (f[-1] == f[-2]).all() and not (f[-1] == f[0]).all()
