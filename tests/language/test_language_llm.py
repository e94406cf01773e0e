"""The LLM backend against a real local HTTP server (127.0.0.1, a bounded number of requests)."""

from __future__ import annotations

import json
import socket

import pytest

import morphosim_gym as ms
from morphosim_gym.language.llm import LLMConfig, parse_llm
from morphosim_gym.language.rules import parse_rules
from tests.language.chat_server import ChatServer


@pytest.fixture
def server_factory():
    servers = []

    def make(replies):
        s = ChatServer(replies)
        servers.append(s)
        return s

    yield make
    for s in servers:
        s.close()


def config(server: ChatServer, **kw) -> LLMConfig:
    return LLMConfig(base_url=server.url, model="tiny-test", api_key="sk-test", timeout_s=5, **kw)


GOOD = json.dumps(parse_rules("a red ball bounces from right to left").to_dict())


def test_valid_reply_is_used(server_factory):
    srv = server_factory([GOOD])
    plan = parse_llm("a red ball bounces from right to left", config=config(srv))
    assert plan.backend == "llm" and plan.objects[0].color.name == "red"
    req = srv.requests[0]
    assert req["path"] == "/v1/chat/completions" and req["auth"] == "Bearer sk-test"
    assert req["body"]["model"] == "tiny-test" and req["body"]["messages"][0]["role"] == "system"
    assert "Categories" in req["body"]["messages"][0]["content"]


def test_code_fenced_reply(server_factory):
    srv = server_factory(["Here you go:\n```json\n" + GOOD + "\n```"])
    assert parse_llm("a red ball bounces", config=config(srv)).mode == "generate"


def test_invalid_then_valid_retries_once_with_the_error(server_factory):
    bad = json.dumps({"mode": "generate", "objects": [{"noun": "ball", "category": "giraffe"}]})
    srv = server_factory([bad, GOOD])
    plan = parse_llm("a red ball bounces from right to left", config=config(srv))
    assert plan.backend == "llm" and len(srv.requests) == 2
    retry = srv.requests[1]["body"]["messages"]
    assert retry[-2]["role"] == "assistant" and "category" in retry[-1]["content"]


def test_invalid_twice_falls_back_to_rules(server_factory):
    srv = server_factory(["not json at all", "{\"mode\": \"dance\"}"])
    plan = parse_llm("a red ball bounces from right to left", config=config(srv))
    assert plan.backend == "rules" and plan == parse_rules("a red ball bounces from right to left")
    assert len(srv.requests) == 2


def test_invalid_twice_raises_when_configured(server_factory):
    srv = server_factory(["nope", "still nope"])
    with pytest.raises(ms.CommandError, match="no valid plan"):
        parse_llm("a red ball bounces", config=config(srv, fallback="raise"))


def test_http_error_falls_back_or_raises(server_factory):
    srv = server_factory([503])
    assert parse_llm("make the bus yellow", config=config(srv)).backend == "rules"
    srv = server_factory([503])
    with pytest.raises(ms.BackendUnavailableError, match="503"):
        parse_llm("make the bus yellow", config=config(srv, fallback="raise"))


def test_unreachable_endpoint():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # closed again before the request: nothing listens there
    cfg = LLMConfig(base_url=f"http://127.0.0.1:{port}/v1", model="m", timeout_s=2, fallback="raise")
    with pytest.raises(ms.BackendUnavailableError, match="unreachable"):
        parse_llm("make the bus yellow", config=cfg)


def test_edit_targets_resolve_against_the_scene(server_factory, scene_factory):
    reply = json.dumps({"mode": "edit", "edits": [{"op": "recolor", "targets": [{"text": "the bus", "noun": "bus"}],
                                                   "mode": "assign", "color": {"name": "yellow"}}]})
    srv = server_factory([reply])
    scene = scene_factory("road", "bus", "car")
    plan = ms.parse("make the bus yellow", scene, backend="llm", llm=config(srv))
    t = plan.edits[0].targets[0]
    assert (t.objects, t.object_ids, plan.edits[0].color.rgb) == (("bus",), (1,), (1.0, 1.0, 0.0))
    assert "bus (bus)" in srv.requests[0]["body"]["messages"][1]["content"]


def test_target_missing_from_scene_is_retried_then_falls_back(server_factory, scene_factory):
    reply = json.dumps({"mode": "edit", "edits": [{"op": "remove", "targets": ["giraffe"]}]})
    srv = server_factory([reply, reply])
    scene = scene_factory("road", "bus", "car")
    plan = ms.parse("delete the bus", scene, backend="llm", llm=config(srv))
    assert plan.backend == "rules" and plan.edits[0].targets[0].objects == ("bus",)


def test_config_from_env_and_dict():
    env = {"MORPHOSIM_LLM_BASE_URL": "http://127.0.0.1:9/v1", "MORPHOSIM_LLM_MODEL": "m",
           "MORPHOSIM_LLM_API_KEY": "k", "MORPHOSIM_LLM_FALLBACK": "raise", "MORPHOSIM_LLM_TIMEOUT_S": "3"}
    cfg = LLMConfig.from_env(env)
    assert cfg.configured and (cfg.api_key, cfg.fallback, cfg.timeout_s) == ("k", "raise", 3.0)
    assert not LLMConfig.from_env({}).configured
    with pytest.raises(ValueError, match="llm.fallback"):
        LLMConfig.from_dict({"fallback": "maybe"})
    with pytest.raises(ValueError, match="llm.colour"):
        LLMConfig.from_dict({"colour": 1})
    with pytest.raises(ValueError, match="llm.base_url"):
        LLMConfig(base_url="ftp://x")


def test_auto_backend_without_endpoint_uses_rules(monkeypatch):
    for var in ("MORPHOSIM_LLM_BASE_URL", "MORPHOSIM_LLM_MODEL"):
        monkeypatch.delenv(var, raising=False)
    assert ms.parse("make the bus yellow", backend="auto").backend == "rules"
    with pytest.raises(ms.CommandError, match="backend"):
        ms.parse("make the bus yellow", backend="gpt")
