"""`morphosim collect`: the LeRobot v3.0 dataset read back with pyarrow and PyAV (features, frames,
indices, tasks, stats, pairing), resuming an interrupted run, refusing another run's folder."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
pytest.importorskip("av")

from morphosim_gym.bench import SuiteError, load_suite, plan_episodes  # noqa: E402
from morphosim_gym.bench.collect import COLLECT_MANIFEST, run_collect, task_suite  # noqa: E402
from morphosim_gym.bench.dataset import load_staged, staged_path  # noqa: E402
from morphosim_gym.bench.dataset.video import read_frames  # noqa: E402
from morphosim_gym.bench.layout import RESULTS_LOG  # noqa: E402
from morphosim_gym.cli import main  # noqa: E402

from .conftest import write_suite  # noqa: E402

POLICIES = ["oracle"]
SUITE = {
    "name": "collect_tiny", "env": "MorphoSim/Track-v0",
    "scenes": {"prompt": "a {color} {object} moves from left to right", "target": "object", "target_color": "color",
               "fields": {"color": ["red", "blue"], "object": ["ball", "cube"]}},
    "env_kwargs": {"width": 32, "height": 32, "control_hz": 2},      # 12 steps of 32 x 32 per episode
    "seed": 0, "episodes": 2, "frames": 0,
    "perturbations": [
        {"name": "recolor_target", "edits": "make the {target} {new_color}"},
        {"name": "reverse_mid", "edits": "reverse the motion of the {target}", "at": 3},
        {"name": "delete_nothing", "edits": "delete the purple giraffe"},          # fails: nothing to delete
    ],
}
DTYPES = {"float32": pa.float32(), "int64": pa.int64(), "bool": pa.bool_()}
STATS = {"min", "max", "mean", "std", "count", "q01", "q10", "q50", "q90", "q99"}
DATASET_PARTS = ("meta", "data", "videos")


@pytest.fixture(scope="module")
def suite():
    return load_suite(SUITE)


@pytest.fixture(scope="module")
def collected(suite, tmp_path_factory, cache_dir):
    out = tmp_path_factory.mktemp("collect") / "tiny"
    return run_collect(suite, POLICIES, out, cache_dir=cache_dir, progress=False)


def _info(out):
    return json.loads((Path(out) / "meta" / "info.json").read_text())


def _data(out):
    return pa.concat_tables([pq.read_table(p) for p in sorted((Path(out) / "data").glob("*/*.parquet"))])


def _episodes(out):
    return pa.concat_tables([pq.read_table(p) for p in sorted((Path(out) / "meta" / "episodes").glob("*/*.parquet"))])


def _files(out):
    """Every dataset file (relative path -> bytes)."""
    root = Path(out)
    return {str(p.relative_to(root)): p.read_bytes() for part in DATASET_PARTS for p in sorted((root / part).rglob("*"))
            if p.is_file()}


def test_run_counts(collected, suite):
    plan = plan_episodes(suite, POLICIES)
    assert collected.ran == len(plan) and collected.resumed == 0
    assert collected.failed == suite.episodes                      # every delete_nothing episode
    assert collected.episodes == len(plan) - suite.episodes
    assert collected.frames == 12 * collected.episodes


def test_info_declares_the_lerobot_features(collected):
    info = _info(collected.out)
    assert info["codebase_version"] == "v3.0" and info["fps"] == 2
    assert info["data_path"] == "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
    assert info["video_path"] == "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
    assert info["splits"] == {"train": f"0:{info['total_episodes']}"}
    f = info["features"]
    assert f["observation.images.eye"]["dtype"] == "video"
    assert f["observation.images.eye"]["shape"] == [32, 32, 3]
    assert f["observation.images.eye"]["names"] == ["height", "width", "channels"]
    vinfo = f["observation.images.eye"]["info"]
    assert vinfo["video.codec"] == "av1" and vinfo["video.fps"] == 2 and vinfo["video.pix_fmt"] == "yuv420p"
    assert (vinfo["video.height"], vinfo["video.width"], vinfo["video.channels"]) == (32, 32, 3)
    assert f["observation.state"] == {"dtype": "float32", "shape": [6], "names": [f"proprio_{i}" for i in range(6)]}
    assert f["action"]["dtype"] == "float32" and f["action"]["shape"] == [3] and len(f["action"]["names"]) == 3
    for key, dtype in {"next.reward": "float32", "next.done": "bool", "next.truncated": "bool",
                       "next.success": "bool", "timestamp": "float32", "frame_index": "int64",
                       "episode_index": "int64", "index": "int64", "task_index": "int64"}.items():
        assert f[key] == {"dtype": dtype, "shape": [1], "names": None}, key


def test_frames_have_every_feature_with_its_dtype_and_shape(collected):
    info = _info(collected.out)
    data = _data(collected.out)
    non_video = {k: v for k, v in info["features"].items() if v["dtype"] != "video"}
    assert data.column_names == list(non_video)                    # exactly the non-video features, in order
    for key, ft in non_video.items():
        t = data.schema.field(key).type
        if ft["shape"] == [1]:
            assert t == DTYPES[ft["dtype"]], key
        else:
            assert pa.types.is_fixed_size_list(t) and t.list_size == ft["shape"][0], key
            assert t.value_type == DTYPES[ft["dtype"]], key
    assert data.num_rows == info["total_frames"]
    assert data.column("index").to_pylist() == list(range(info["total_frames"]))
    assert np.isfinite(np.asarray(data.column("action").combine_chunks().flatten())).all()


def test_episodes_are_contiguous_and_match_their_video_frames(collected):
    info = _info(collected.out)
    data, eps = _data(collected.out), _episodes(collected.out)
    rows = eps.to_pylist()
    assert [r["episode_index"] for r in rows] == list(range(info["total_episodes"]))
    ep_col = np.asarray(data.column("episode_index"))
    frame_col = np.asarray(data.column("frame_index"))
    ts_col = np.asarray(data.column("timestamp"))
    end = 0
    for r in rows:
        a, b = r["dataset_from_index"], r["dataset_to_index"]
        assert a == end and b - a == r["length"] == 12
        end = b
        assert (ep_col[a:b] == r["episode_index"]).all()
        assert frame_col[a:b].tolist() == list(range(r["length"]))
        np.testing.assert_allclose(ts_col[a:b], np.arange(r["length"]) / info["fps"], atol=1e-6)
        key = "videos/observation.images.eye"
        path = collected.out / info["video_path"].format(video_key="observation.images.eye",
                                                         chunk_index=r[f"{key}/chunk_index"],
                                                         file_index=r[f"{key}/file_index"])
        frames, times = read_frames(path, r[f"{key}/from_timestamp"], r[f"{key}/to_timestamp"])
        assert len(frames) == r["length"] and frames.shape[1:] == (32, 32, 3)
        # LeRobot queries from_timestamp + timestamp within a tolerance of 1e-4 s
        np.testing.assert_allclose(times - r[f"{key}/from_timestamp"], ts_col[a:b], atol=1e-4)
        staged = load_staged(staged_path(collected.out, _key(r)))
        assert np.abs(frames.astype(int) - staged.observations["rgb"].astype(int)).mean() < 12   # lossy, close
        np.testing.assert_array_equal(np.asarray(data.column("observation.state").combine_chunks().flatten())
                                      .reshape(-1, 6)[a:b], staged.observations["proprio"])
    assert end == info["total_frames"] == data.num_rows


def _key(row):
    from morphosim_gym.bench import EpisodeKey

    return EpisodeKey(row["policy"], row["perturbation"], row["seed"])


def test_task_indices_resolve_to_the_instructions(collected):
    info = _info(collected.out)
    tasks = pq.read_table(collected.out / "meta" / "tasks.parquet")
    assert tasks.column_names == ["task_index", "task"]
    assert json.loads(tasks.schema.metadata[b"pandas"])["index_columns"] == ["task"]   # pandas restores the index
    by_index = dict(zip(tasks.column("task_index").to_pylist(), tasks.column("task").to_pylist()))
    assert sorted(by_index) == list(range(info["total_tasks"])) and info["total_tasks"] >= 1
    data, eps = _data(collected.out), _episodes(collected.out)
    task_col = data.column("task_index").to_pylist()
    for r in eps.to_pylist():
        used = {by_index[i] for i in task_col[r["dataset_from_index"]:r["dataset_to_index"]]}
        assert used == set(r["tasks"])
        assert all("centre" in t for t in r["tasks"])                  # the Track instruction


def test_stats_cover_every_feature_with_lerobot_shapes(collected):
    info = _info(collected.out)
    stats = json.loads((collected.out / "meta" / "stats.json").read_text())
    assert set(stats) == set(info["features"])
    for key, ft in info["features"].items():
        assert set(stats[key]) == STATS, key
        shape = (3, 1, 1) if ft["dtype"] == "video" else tuple(ft["shape"])
        for name, value in stats[key].items():
            assert np.asarray(value).shape == ((1,) if name == "count" else shape), (key, name)
        assert stats[key]["count"] == [info["total_frames"]]
    img = stats["observation.images.eye"]
    assert 0.0 <= np.min(img["min"]) <= np.max(img["max"]) <= 1.0
    data = _data(collected.out)
    actions = np.asarray(data.column("action").combine_chunks().flatten()).reshape(-1, 3)
    np.testing.assert_allclose(stats["action"]["mean"], actions.mean(axis=0), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(stats["action"]["std"], actions.std(axis=0), rtol=1e-4, atol=1e-6)
    ep = _episodes(collected.out)
    assert np.asarray(ep.column("stats/action/mean").to_pylist()).shape == (info["total_episodes"], 3)


def test_paired_metadata_names_the_base_twin(collected, suite):
    rows = _episodes(collected.out).to_pylist()
    assert {r["perturbation"] for r in rows} == {"base", "recolor_target", "reverse_mid"}
    for r in rows:
        base = rows[r["base_episode_index"]]
        assert base["perturbation"] == "base" and base["seed"] == r["seed"] and base["policy"] == r["policy"]
        assert (base["prompt"], base["scene_seed"], base["target"]) == (r["prompt"], r["scene_seed"], r["target"])
        if r["perturbation"] == "base":
            assert r["base_episode_index"] == r["episode_index"] and r["edits"] == [] and not r["perturbed"]
        else:
            assert r["edits"] and r["perturbed"] and r["edits"][0].startswith(("make the", "reverse the"))
    assert {r["edit_step"] for r in rows if r["perturbation"] == "reverse_mid"} == {3}


def test_interrupted_run_resumes_to_the_same_dataset(collected, suite, tmp_path, cache_dir):
    """A run killed after 3 episodes (log lines fsync'd, a torn 4th line, the 4th episode's steps staged
    but not logged, the dataset never written) finishes to byte-identical files."""
    out = tmp_path / "resumed"
    (out / ".staging").mkdir(parents=True)
    shutil.copy(collected.out / COLLECT_MANIFEST, out / COLLECT_MANIFEST)
    lines = (collected.out / RESULTS_LOG).read_bytes().splitlines(keepends=True)
    (out / RESULTS_LOG).write_bytes(b"".join(lines[:3]) + lines[3][:25])
    plan = {k.id: k for k in plan_episodes(suite, POLICIES)}
    for line in lines[:3]:
        key = plan[json.loads(line)["key"]]
        if staged_path(collected.out, key).exists():
            shutil.copy(staged_path(collected.out, key), staged_path(out, key))
    orphan = plan[json.loads(lines[3])["key"]]
    staged_path(out, orphan).write_bytes(b"half an npz")            # replaced when the episode reruns
    (out / "data").mkdir()
    (out / "data" / "stale.parquet").write_bytes(b"from the killed run")
    result = run_collect(suite, POLICIES, out, cache_dir=cache_dir, progress=False)
    assert (result.ran, result.resumed) == (len(plan) - 3, 3)
    keys = [json.loads(x)["key"] for x in (out / RESULTS_LOG).read_text().splitlines()]
    assert len(keys) == len(set(keys)) == len(plan)                 # nothing lost, nothing duplicated
    assert _files(out) == _files(collected.out)


def test_rerun_of_a_complete_run_runs_nothing(collected, suite, cache_dir):
    before = _files(collected.out)
    again = run_collect(suite, POLICIES, collected.out, cache_dir=cache_dir, progress=False)
    assert (again.ran, again.resumed) == (0, len(plan_episodes(suite, POLICIES)))
    assert _files(collected.out) == before


def test_another_runs_folder_is_refused(collected, suite, cache_dir):
    with pytest.raises(SuiteError, match="another run.*policies"):
        run_collect(suite, ["oracle", "random"], collected.out, cache_dir=cache_dir, progress=False)
    other = load_suite(dict(SUITE, perturbations=SUITE["perturbations"][:1]))
    with pytest.raises(SuiteError, match="another run.*digest"):
        run_collect(other, POLICIES, collected.out, cache_dir=cache_dir, progress=False)


def test_a_folder_of_something_else_is_refused(tmp_path, suite, cache_dir):
    (tmp_path / RESULTS_LOG).write_text("")                          # e.g. a morphosim bench sweep
    (tmp_path / "data").mkdir()
    with pytest.raises(SuiteError, match="not empty.*not a morphosim collect folder"):
        run_collect(suite, POLICIES, tmp_path, cache_dir=cache_dir, progress=False)
    assert (tmp_path / "data").is_dir() and not (tmp_path / COLLECT_MANIFEST).exists()


def test_task_suite_has_only_base_episodes():
    s = task_suite("track", episodes=3, seed=5, env_kwargs={"width": 32, "height": 32})
    assert s.env_id == "MorphoSim/Track-v0" and s.perturbations == () and s.seeds == [5, 6, 7]
    with pytest.raises(SuiteError, match="task name"):
        task_suite("no_such_task")


def test_cli_collect_h264(tmp_path, cache_dir, capsys):
    path = write_suite(tmp_path / "suite.yaml", dict(SUITE, episodes=1, perturbations=SUITE["perturbations"][:1]))
    out = tmp_path / "cli"
    code = main(["collect", str(path), "--out", str(out), "--vcodec", "h264", "--cache-dir", cache_dir,
                 "--no-progress"])
    assert code == 0, capsys.readouterr().err
    assert "2 episodes, 24 frames (2 run, 0 resumed, 0 failed)" in capsys.readouterr().out
    assert _info(out)["features"]["observation.images.eye"]["info"]["video.codec"] == "h264"
    with pytest.raises(SystemExit):                                                   # a suite and a task
        main(["collect", str(path), "--task", "track"])
    assert main(["collect", str(path), "--out", str(out), "--policy", "random", "--cache-dir", cache_dir,
                 "--no-progress"]) == 255
    assert "another run" in capsys.readouterr().err


@pytest.mark.slow
def test_ray_backend_writes_the_same_dataset(collected, suite, tmp_path, cache_dir):
    pytest.importorskip("ray")
    ray_result = run_collect(suite, POLICIES, tmp_path / "ray", backend="ray", workers=2, cache_dir=cache_dir,
                             progress=False)
    assert (ray_result.ran, ray_result.failed) == (collected.ran, collected.failed)
    assert _files(ray_result.out) == _files(collected.out)


def test_reads_as_lerobot_reads(collected):
    """LeRobot's reading path (from its v3.0 code): tasks through pandas, frames through `datasets` with
    the features' HF types, a frame's video time = from_timestamp + timestamp within 1e-4 s."""
    pd = pytest.importorskip("pandas")
    datasets = pytest.importorskip("datasets")
    info = _info(collected.out)
    tasks = pd.read_parquet(collected.out / "meta" / "tasks.parquet")
    assert tasks.index.name == "task" and list(tasks.columns) == ["task_index"]
    hf = {k: datasets.Value(f["dtype"]) if f["shape"] == [1] else
          datasets.Sequence(length=f["shape"][0], feature=datasets.Value(f["dtype"]))
          for k, f in info["features"].items() if f["dtype"] != "video"}
    data = datasets.Dataset.from_parquet([str(p) for p in sorted((collected.out / "data").glob("*/*.parquet"))],
                                         features=datasets.Features(hf))
    eps = datasets.Dataset.from_parquet([str(p) for p in
                                         sorted((collected.out / "meta" / "episodes").glob("*/*.parquet"))])
    assert len(data) == info["total_frames"] and len(eps) == info["total_episodes"]
    item = data[len(data) - 1]
    ep = eps[item["episode_index"]]
    assert isinstance(tasks.iloc[item["task_index"]].name, str)
    key = "videos/observation.images.eye"
    path = collected.out / info["video_path"].format(video_key="observation.images.eye",
                                                     chunk_index=ep[f"{key}/chunk_index"],
                                                     file_index=ep[f"{key}/file_index"])
    _, times = read_frames(path, ep[f"{key}/from_timestamp"], ep[f"{key}/to_timestamp"])
    assert np.min(np.abs(times - (ep[f"{key}/from_timestamp"] + item["timestamp"]))) <= 1e-4
