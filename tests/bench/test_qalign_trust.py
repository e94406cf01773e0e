"""A Q-Align model folder's own Python code runs only behind an explicit flag."""

import json

import pytest

from morphosim_gym.bench.quality import QualityConfig
from morphosim_gym.bench.semantic import load_qalign, remote_code_files


@pytest.fixture
def code_folder(tmp_path):
    """A model folder whose code, if imported, leaves a marker file (what a hostile folder could do)."""
    folder = tmp_path / "qalign"
    folder.mkdir()
    marker = tmp_path / "code-ran"
    (folder / "config.json").write_text(json.dumps({
        "model_type": "mplug_owl2", "auto_map": {"AutoConfig": "configuration_evil.EvilConfig",
                                                 "AutoModelForCausalLM": "modeling_evil.EvilModel"}}))
    for name in ("configuration_evil.py", "modeling_evil.py"):
        (folder / name).write_text(f"import pathlib\npathlib.Path({str(marker)!r}).write_text('ran')\n")
    return folder, marker


def test_a_folder_with_code_is_refused_without_the_flag(code_folder):
    folder, marker = code_folder
    assert remote_code_files(folder) == ["configuration_evil.py", "modeling_evil.py", "config.json auto_map"]
    with pytest.raises(ValueError, match="--trust-remote-code"):
        load_qalign(str(folder))
    with pytest.raises(ValueError, match="trust_remote_code=True"):
        load_qalign(str(folder), trust_remote_code=False)
    assert not marker.exists()


def test_the_flag_reaches_the_loader(code_folder, monkeypatch):
    from morphosim_gym.cli import build_parser

    args = build_parser().parse_args(["quality", "a red ball", "--trust-remote-code"])
    assert args.trust_remote_code is True
    assert build_parser().parse_args(["quality", "a red ball"]).trust_remote_code is False
    assert QualityConfig().trust_remote_code is False
    pytest.importorskip("transformers")
    folder, marker = code_folder
    scorer, why = load_qalign(str(folder), trust_remote_code=True)    # asked for: the folder's code runs
    assert marker.exists() and scorer is None and "could not load Q-Align" in why
