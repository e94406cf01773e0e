"""Fixtures of the benchmark tests: a scene cache shared by the session, suite files written on the fly."""

from pathlib import Path

import pytest
import yaml

import morphosim_gym  # noqa: F401  (registers the env ids)

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory) -> str:
    """One scene cache for every test (scenes are generated once, as in a real sweep)."""
    return str(tmp_path_factory.mktemp("scene_cache"))


def write_suite(path: Path, data: dict) -> Path:
    """Write a suite mapping as a YAML file."""
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def strip_timing(records: list[dict]) -> list[dict]:
    """Records without their timing fields (the only ones that may differ between identical runs)."""
    from morphosim_gym.bench.report import TIMING_FIELDS

    return [{k: v for k, v in r.items() if k not in TIMING_FIELDS} for r in records]
