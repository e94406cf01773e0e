"""The parser's dispatch tables: complete, unambiguous, and in registration order."""

from morphosim_gym.language.lexicon import EDIT_VERB_GROUPS
from morphosim_gym.language.rules import edits
from morphosim_gym.language.rules.dispatch import NUMBER, WordTable
from morphosim_gym.language.rules.motion import Predicate
from morphosim_gym.language.rules.scanner import PhraseScanner
from morphosim_gym.language.rules.tokens import tokenize


def test_every_edit_verb_group_has_one_reader_and_every_verb_one_group():
    assert set(edits._GROUP_READERS) == set(EDIT_VERB_GROUPS)
    verbs = [v for vs in EDIT_VERB_GROUPS.values() for v in vs]
    assert len(verbs) == len(set(verbs))
    assert set(edits._VERB_READERS) == set(verbs)


def test_word_table_keeps_registration_order_and_keys_digits_as_numbers():
    table = WordTable()
    table.on("a", "b")(lambda: "ab")
    table.any_word(lambda: "any")
    table.on(["b"], NUMBER)(lambda: "b-or-number")
    assert [h() for h in table.handlers_for("b")] == ["ab", "any", "b-or-number"]
    assert [h() for h in table.handlers_for("a")] == ["ab", "any"]
    assert [h() for h in table.handlers_for("2.5")] == ["any", "b-or-number"]
    assert [h() for h in table.handlers_for("zebra")] == ["any"]


def test_the_scanner_reads_each_construction_once():
    toks = tokenize("from left to right twice as fast in circles around the tree clockwise")
    pred = Predicate()
    assert PhraseScanner(toks).scan(0, len(toks), pred) == len(toks)
    assert pred.from_side[1] == "from left" and pred.to_side[1] == "to right"
    assert pred.factor == 2.0 and pred.path == "circle" and pred.around.head == "tree" and pred.clockwise is True


def test_the_scanner_stops_at_a_boundary_and_notes_unknown_words():
    toks = tokenize("slowly blorfs and a cat")
    pred = Predicate()
    assert PhraseScanner(toks).scan(0, len(toks), pred, boundary=lambda k: toks[k] == "and") == 2
    assert pred.speed == 0.5 and pred.unknown == ["blorfs"]
