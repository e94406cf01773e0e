"""`morphosim parse` prints the plan as JSON."""

import json

from morphosim_gym.cli import main
from morphosim_gym.language.plan import Plan


def test_parse_prints_json(capsys):
    assert main(["parse", "a red ball bounces from right to left"]) == 0
    out = capsys.readouterr().out
    plan = Plan.from_dict(json.loads(out))
    assert plan.mode == "generate" and plan.motions[0].path == "bounce"


def test_parse_compact_and_words(capsys):
    assert main(["parse", "--compact", "make", "the", "bus", "yellow"]) == 0
    out = capsys.readouterr().out.strip()
    assert "\\n" not in out and json.loads(out)["edits"][0]["color"]["name"] == "yellow"


def test_parse_error_exit_code(capsys):
    assert main(["parse", "make the bus blurple"]) == 2
    assert "blurple" in capsys.readouterr().err
    assert main(["parse", "--require-scene", "make the bus yellow"]) == 2
