"""The labelled corpus: exact-plan accuracy >= 95 %, per-field report printed (run with -s to see it)."""

from pathlib import Path

from morphosim_gym.language.evaluate import canonical_label, evaluate, format_report, load_corpus

CORPUS = Path(__file__).with_name("corpus.jsonl")
HELDOUT = Path(__file__).with_name("heldout.jsonl")  # written after tuning on CORPUS; see the language README


def test_corpus_is_large_and_well_formed():
    items = load_corpus(CORPUS)
    assert len(items) >= 300
    kinds = {it["kind"] for it in items}
    assert {"paper", "generate", "edit", "compound", "paraphrase", "typo", "error"} <= kinds
    assert len({it["id"] for it in items}) == len(items)
    for it in items:
        canonical_label(it["expect"])  # every label expands


def test_corpus_accuracy(minilm):
    rep = evaluate(load_corpus(CORPUS))
    print("\n" + format_report(rep))
    for f in rep["failures"]:
        print(f"  failed [{f['id']}] {f['text']!r}")
    assert rep["exact"] >= 0.95, format_report(rep)
    # the paper's own examples all parse exactly
    assert rep["by_kind"]["paper"][0] == rep["by_kind"]["paper"][1]


def test_heldout_accuracy(minilm):
    rep = evaluate(load_corpus(HELDOUT))
    print("\nheld-out: " + format_report(rep).splitlines()[0])
    assert rep["exact"] >= 0.95, format_report(rep)
