"""The result log survives a torn last line; bootstrap intervals behave."""

import json

import numpy as np

from morphosim_gym.bench.stats import bootstrap_mean, summarize
from morphosim_gym.bench.store import ResultStore


def test_torn_last_line_is_dropped_and_cut_before_appending(tmp_path):
    path = tmp_path / "results.jsonl"
    store = ResultStore(path)
    with store:
        store.append({"key": "a", "v": 1})
        store.append({"key": "b", "v": 2})
    with open(path, "ab") as fh:
        fh.write(b'{"key": "c", "v"')                     # a writer killed mid-line
    assert sorted(ResultStore(path).load()) == ["a", "b"]
    with ResultStore(path) as again:
        again.append({"key": "c", "v": 3})
    lines = path.read_bytes().decode().splitlines()
    assert [json.loads(x)["key"] for x in lines] == ["a", "b", "c"]


def test_bootstrap_interval_contains_the_mean_and_shrinks_with_data():
    rng = np.random.default_rng(1)
    small, large = bootstrap_mean(rng.normal(1.0, 1.0, 10)), bootstrap_mean(rng.normal(1.0, 1.0, 1000))
    for iv in (small, large):
        assert iv.low <= iv.mean <= iv.high
    assert large.high - large.low < (small.high - small.low) / 3
    assert abs(large.mean - 1.0) < 0.15 and large.low < 1.0 < large.high
    same = bootstrap_mean([0.5] * 7)
    assert same.low == same.high == 0.5 and bootstrap_mean([]).n == 0


def test_paired_difference_uses_same_seed_pairs_only():
    def rec(p, seed, success, ret, status="ok"):
        return {"policy": "x", "perturbation": p, "seed": seed, "status": status, "success": success, "return": ret}

    records = [rec("base", 0, True, 10.0), rec("base", 1, False, 2.0), rec("base", 2, True, 8.0, status="failed"),
               rec("p", 0, False, 4.0), rec("p", 1, False, 1.0), rec("p", 2, True, 9.0)]
    base, pert = summarize(records, ["x"], ["base", "p"])
    assert base.failed == 1 and base.delta_return is None
    assert pert.delta_return.n == 2                         # seed 2's base failed: no pair
    assert pert.delta_return.mean == -3.5                   # ((4 - 10) + (1 - 2)) / 2
    assert pert.delta_success.mean == -0.5
