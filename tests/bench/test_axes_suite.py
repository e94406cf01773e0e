"""The axis suites (one per task, every registry axis), per-episode errors for axes that do not apply,
and the paired-vs-unpaired power statement of the report."""

import json

import numpy as np
import pytest

from morphosim_gym.bench.perturb import PerturbationError, resolve_edits
from morphosim_gym.bench.stats import bootstrap_difference, power
from morphosim_gym.bench.suite import SuiteError, load_suite
from morphosim_gym.tasks.axes import AXES


@pytest.mark.parametrize("name", ["axes_track", "axes_reach", "axes_find"])
def test_axis_suites_cover_every_axis(name):
    suite = load_suite(name)
    assert [p.name for p in suite.perturbations] == list(AXES)
    assert not [p.error for p in suite.perturbations if p.error]
    rev = suite.perturbation("reverse_target_mid")
    assert rev.at == 20 and rev.edits == AXES["reverse_target_mid"].edits
    assert suite.perturbation("camera_shift").camera.orbit_deg == 25.0


def test_axis_entries_take_overrides_and_reject_unknown_axes():
    suite = load_suite({"name": "s", "env": "MorphoSim/Track-v0",
                        "perturbations": [{"axis": "light_dim", "at": 5}, {"axis": "sensor_noise", "name": "noise2"}]})
    assert [(p.name, p.at) for p in suite.perturbations] == [("light_dim", 5), ("noise2", 0)]
    bad = load_suite({"name": "s", "env": "MorphoSim/Track-v0", "perturbations": [{"axis": "nope"}]})
    assert "Unknown axis 'nope'" in bad.perturbations[0].error
    with pytest.raises(SuiteError, match="Unknown axis"):
        load_suite({"name": "s", "env": "MorphoSim/Track-v0", "axes": ["nope"]})


def test_an_axis_that_does_not_apply_is_a_clear_per_episode_error():
    suite = load_suite("axes_track")
    values = {"target": "red ball", "target_noun": "ball", "target_color": "red", "distractor": None,
              "distractor_noun": None, "new_color": "blue", "ground": "ground", "swap_noun": "cube"}
    for name in ("remove_distractor", "recolor_distractor", "distractor_motion"):
        with pytest.raises(PerturbationError, match=r"needs \{distractor\}"):
            resolve_edits(suite.perturbation(name), values)
    assert resolve_edits(suite.perturbation("target_size"), values) == ("make the red ball twice as big",)


def _records(x, y, perturbation="p"):
    recs = []
    for seed, (a, b) in enumerate(zip(x, y)):
        recs.append({"policy": "pi", "perturbation": "base", "seed": seed, "status": "ok", "return": b,
                     "success": b > 0})
        recs.append({"policy": "pi", "perturbation": perturbation, "seed": seed, "status": "ok", "return": a,
                     "success": a > 0})
    return recs


def test_power_paired_interval_is_narrower_on_correlated_episodes():
    rng = np.random.default_rng(0)
    base = rng.normal(0.0, 1.0, 40)
    pert = base - 0.3 + rng.normal(0.0, 0.1, 40)          # seed effects shared: pairing removes them
    (row,) = [p for p in power(_records(pert, base), ["pi"], ["base", "p"]) if p.metric == "return"]
    assert row.pairs == 40
    assert row.paired_width < 0.25 * row.unpaired_width
    assert row.episode_ratio == pytest.approx((row.unpaired_width / row.paired_width) ** 2)
    assert 0.9 < row.saved < 1.0
    # independent episodes: pairing buys nothing (ratio near 1)
    indep = rng.normal(0.0, 1.0, 400)
    (row2,) = [p for p in power(_records(indep, rng.normal(0.0, 1.0, 400)), ["pi"], ["base", "p"])
               if p.metric == "return"]
    assert 0.7 < row2.episode_ratio < 1.4
    iv = bootstrap_difference([1.0, 2.0, 3.0], [0.0, 0.0, 0.0])
    assert iv.mean == 2.0 and iv.low < 2.0 < iv.high


def test_power_of_identical_conditions_is_not_a_number():
    (row, srow) = power(_records([1.0, 1.0], [1.0, 1.0]), ["pi"], ["base", "p"])
    assert np.isnan(row.episode_ratio) and row.as_dict()["episode_ratio"] is None
    same = power(_records([1.0, 2.0, 3.0], [0.0, 1.0, 2.0]), ["pi"], ["base", "p"])[0]
    assert same.paired_width == 0.0 and same.episode_ratio == float("inf") and same.as_dict()["episode_ratio"] == "inf"


def test_report_states_power(tmp_path):
    from morphosim_gym.bench.report import write_outputs
    from morphosim_gym.bench.stats import summarize

    suite = load_suite({"name": "s", "env": "MorphoSim/Track-v0", "episodes": 3, "frames": 0,
                        "perturbations": [{"axis": "light_dim"}]})
    recs = _records([0.5, 1.5, 2.0], [1.0, 2.0, 3.0], "light_dim")
    for r in recs:
        r.update(key=f"{r['perturbation']}/{r['seed']}")
    summaries = summarize(recs, ["pi"], ["base", "light_dim"])
    write_outputs(tmp_path, suite, ["pi"], recs, summaries, {"backend": "local"})
    report = (tmp_path / "report.md").read_text()
    assert "## Statistical power: paired vs unpaired design" in report and "| light_dim | return | 3 |" in report
    data = json.loads((tmp_path / "results.json").read_text())
    assert {p["metric"] for p in data["power"]} == {"return", "success"}
    assert (tmp_path / "power.png").exists()
