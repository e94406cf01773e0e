"""Follow-ups of a generate plan: motion stages the generator plays, and edits applied after it.

"the ball rolls left then stops" parses as a generate plan with one follow-up, "stops", whose edit
stops the ball. A follow-up without a subject ("then stops", "then reverses", "then speeds up")
continues the motion: it is a *second stage* of the clip (the ball rolls left for the first half, then
stays where it is), which the generator plays (`motion_stages`). Every other follow-up ("; then make
it blue", "then disappears") is an edit of the generated scene (`follow_up_edits`), given as the
text an editor parses on its own ("disappears" -> "remove the ball").

A motion has at most two stages: a second continuation of the same object ("... then stops then
reverses") is refused with a `CommandError` naming it.
"""

from __future__ import annotations

from typing import Any

from ..errors import CommandError
from .lexicon import CONTINUATIONS

__all__ = ["STAGE_OPS", "is_continuation", "motion_stages", "follow_up_edits"]

STAGE_OPS = ("stop", "reverse", "speed")


def _words(text: str) -> list[str]:
    from .rules.tokens import tokenize

    return tokenize(text)


def _continuation_verb(words: list[str]) -> str | None:
    """The edit verb of a subject-less follow-up ("stops" -> "stop"; a bare "reverse", as the typo
    repair writes "reverses", is its own), else None."""
    if words and words[0] in CONTINUATIONS:
        return CONTINUATIONS[words[0]]
    if len(words) == 1 and words[0] in _BARE:
        return words[0]
    return None


_BARE = frozenset(CONTINUATIONS.values())


def is_continuation(text: str) -> bool:
    """Whether a follow-up is a subject-less motion verb ("stops", "then reverses", "speeds up")."""
    return _continuation_verb(_words(text)) is not None


def _is_stage(follow: Any, names: set[str]) -> bool:
    return (follow.mode == "edit" and bool(follow.edits) and is_continuation(follow.text)
            and all(op.op in STAGE_OPS and all(set(t.objects) <= names and t.objects for t in op.targets)
                    for op in follow.edits))


def motion_stages(plan: Any) -> dict[str, Any]:
    """Object name -> the stop / reverse / speed `EditOp` its motion continues with from mid-clip.

    Raises:
        CommandError: an object with more than two stages, or a second stage of an object that does not
            move (the parser checks this, so a plan it returns always generates).
    """
    names = {o.name for o in plan.objects}
    moving = {m.target for m in plan.motions if m.path != "stop"}
    stages: dict[str, Any] = {}
    for follow in plan.then:
        if not _is_stage(follow, names):
            continue
        for op in follow.edits:
            for t in op.targets:
                for name in t.objects:
                    if name in stages:
                        raise CommandError(f"Could not honour {plan.text!r}: a motion has at most two stages; "
                                           f"{name!r} already {stages[name].op}s before {follow.text!r}")
                    if name not in moving:
                        raise CommandError(f"Could not honour {plan.text!r}: {name!r} does not move before "
                                           f"{follow.text!r}; describe its motion first (e.g. 'the {name} rolls "
                                           f"left then stops')")
                    stages[name] = op
    return stages


def follow_up_edits(plan: Any) -> list[str]:
    """The follow-ups that edit the generated scene, as texts an editor parses without the description."""
    names = {o.name for o in plan.objects}
    out = []
    for follow in plan.then:
        if _is_stage(follow, names):
            continue
        words = _words(follow.text)
        verb = _continuation_verb(words)
        if verb is not None and follow.edits and follow.edits[0].targets:
            nouns = " and ".join(f"the {t.noun}" for t in follow.edits[0].targets)
            out.append(" ".join([verb, nouns] + words[1:]))
        else:
            out.append(follow.text)
    return out
