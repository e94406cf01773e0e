"""SimConfig(parser=..., llm=...) parses prompts AND edits, in MorphoSim and in the envs, against a real
local OpenAI-compatible server on 127.0.0.1 (a bounded number of requests, bounded waits)."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.language.llm import LLMConfig
from morphosim_gym.language.rules import parse_rules
from tests.language.chat_server import ChatServer

SMALL = ms.GenerationConfig(width=32, height=32, num_frames=3, detail=0.2, assets="off")
PROMPT = "a red ball rolls from right to left"


class PlanServer(ChatServer):
    """Answers each chat request with the next scripted plan (a dict, sent as the message content);
    `prompts` are the user messages it was sent."""

    def __init__(self, replies: list[dict]) -> None:
        super().__init__([json.dumps(r) for r in replies])

    @property
    def prompts(self) -> list[str]:
        return [r["body"]["messages"][-1]["content"] for r in self.requests]

    def config(self) -> LLMConfig:
        # fallback="raise": a parse that does not reach the server (or gets no valid plan) fails loudly
        return LLMConfig(base_url=self.url, model="tiny-test", timeout_s=10, fallback="raise", max_retries=0)


@pytest.fixture
def server_factory():
    servers = []

    def make(replies):
        servers.append(PlanServer(replies))
        return servers[-1]

    yield make
    for s in servers:
        s.close()


def test_morphosim_parse_and_edit_go_through_the_configured_llm(server_factory):
    generate = parse_rules(PROMPT).to_dict()
    scene = ms.MorphoSim(generation=SMALL, reconstruction="oracle").generate(PROMPT, seed=0)
    # the edit text asks for green; the server answers blue: a blue ball proves the editor asked the server
    blue = parse_rules("make the ball blue", scene).to_dict()
    srv = server_factory([generate, blue])
    sim = ms.MorphoSim(ms.SimConfig(parser="llm", llm=srv.config(), generation=SMALL, reconstruction="oracle"))
    assert sim.parser.name == "llm" and sim.editor.parser is sim.parser
    plan = sim.parse(PROMPT)
    assert plan.backend == "llm" and plan.mode == "generate" and len(srv.requests) == 1
    edited = sim.edit(scene, "make the ball green")
    assert len(srv.requests) == 2 and "make the ball green" in srv.prompts[1]
    ball = scene.gaussians.object_ids == scene.object("ball").id
    np.testing.assert_allclose(edited.gaussians.colors[ball].mean(axis=0), [0.0, 0.0, 1.0], atol=0.2)
    # the rule parser would have made it green: the editor did not bypass the configured parser
    green = ms.MorphoSim(generation=SMALL, reconstruction="oracle").edit(scene, "make the ball green")
    assert not np.allclose(green.gaussians.colors[ball], edited.gaussians.colors[ball])


def test_env_prompts_and_reset_edits_use_the_configured_parser(server_factory):
    scene = ms.MorphoSim(generation=SMALL, reconstruction="oracle").generate(PROMPT, seed=0)
    srv = server_factory([parse_rules(PROMPT).to_dict(), parse_rules("make the ball blue", scene).to_dict()])
    sim = ms.SimConfig(parser="llm", llm=srv.config(), generation=SMALL, reconstruction="oracle")
    env = gym.make("MorphoSim/Track-v0", sim=sim, prompt=PROMPT, scene_seed=0, width=16, height=16)
    try:
        _, info = env.reset(seed=0, options={"edits": ["make the ball green"]})
        edited = env.unwrapped.scene
    finally:
        env.close()
    assert len(srv.requests) == 2 and info["edits"] == ("make the ball green",)
    ball = edited.gaussians.object_ids == edited.object("ball").id
    np.testing.assert_allclose(edited.gaussians.colors[ball].mean(axis=0), [0.0, 0.0, 1.0], atol=0.2)


def test_auto_parser_without_endpoint_is_the_rule_parser(monkeypatch):
    for var in ("MORPHOSIM_LLM_BASE_URL", "MORPHOSIM_LLM_MODEL"):
        monkeypatch.delenv(var, raising=False)
    sim = ms.MorphoSim(parser="auto", generation=SMALL, reconstruction="oracle")
    assert sim.parse(PROMPT) == parse_rules(PROMPT)


def test_llm_parser_with_an_unreachable_endpoint_fails_or_falls_back_as_configured():
    # a port nothing listens on (bind, read the port, close): connection refused, quickly
    import socket

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    url = f"http://127.0.0.1:{port}/v1"
    strict = ms.MorphoSim(parser="llm", llm=LLMConfig(base_url=url, model="m", timeout_s=3, fallback="raise"))
    with pytest.raises(ms.BackendUnavailableError):
        strict.parse(PROMPT)
    lenient = ms.MorphoSim(parser="llm", llm=LLMConfig(base_url=url, model="m", timeout_s=3))
    assert lenient.parse(PROMPT) == parse_rules(PROMPT)


def test_bad_llm_setting_is_a_clear_error():
    with pytest.raises(ValueError, match="Expected llm as an LLMConfig"):
        ms.SimConfig(parser="llm", llm="http://127.0.0.1:1/v1")
    with pytest.raises(ValueError, match="llm.timeout_s"):
        ms.SimConfig(parser="llm", llm={"base_url": "http://127.0.0.1:1/v1", "timeout_s": -1})
    assert ms.SimConfig(llm={"base_url": "http://127.0.0.1:1/v1", "model": "m"}).llm.configured
    with pytest.raises(ms.CommandError, match="'rules', 'llm', 'auto', or 'module:factory'.*'gpt'"):
        ms.parse("make the bus blue", backend="gpt")
