"""`parse` and `generate` agree on every sentence of the labelled corpus: what parse accepts as a scene
description generates (a tiny clip: 2 frames, 32 px), and what parse refuses generate refuses with the
same message. Edit commands (parse accepts them; generate asks for a description) are left out."""

import time
from pathlib import Path

import pytest

import morphosim_gym as ms
from morphosim_gym.language.evaluate import load_corpus

CORPUS_PATH = Path(__file__).with_name("corpus.jsonl")


def _sentences():
    return [it["text"] for it in load_corpus(CORPUS_PATH) if not it.get("scene")]


@pytest.fixture(scope="module")
def tiny_sim():
    return ms.MorphoSim(generation=ms.GenerationConfig(width=32, height=32, num_frames=2, detail=0.2),
                        reconstruction="oracle")


def _outcome(fn):
    try:
        return "ok", fn()
    except ms.CommandError as exc:
        return "refused", str(exc)


@pytest.mark.slow          # ~50 s on a loaded 2-core machine (302 sentences generated)
@pytest.mark.filterwarnings("ignore::UserWarning")
def test_parse_and_generate_agree_on_the_corpus(tiny_sim):
    start = time.perf_counter()
    agree, disagree, edits = 0, [], 0
    for text in _sentences():
        kind, parsed = _outcome(lambda: ms.parse(text))
        if kind == "ok" and parsed.mode == "edit":
            edits += 1
            continue
        gen_kind, generated = _outcome(lambda: tiny_sim.reconstruct(tiny_sim.generate_clip(text, seed=0)))
        if kind == "ok" and gen_kind == "ok" and isinstance(generated, ms.Scene4D):
            agree += 1
        elif kind == gen_kind == "refused" and parsed == generated:
            agree += 1
        else:
            disagree.append((text, kind, gen_kind, generated if gen_kind == "refused" else ""))
    print(f"parse/generate agree on {agree} of {agree + len(disagree)} corpus sentences ({edits} edit commands "
          f"left out) in {time.perf_counter() - start:.1f} s")
    assert not disagree, disagree
