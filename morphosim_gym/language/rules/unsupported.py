"""Actions the generator cannot honour, refused by name instead of dropped in silence.

Objects in a generated scene move on their own paths (straight, bounce, circle, towards a landmark,
towards each other, falling); nothing acts on another object. A description whose verb handles
another object ("a robot arm picks up a red cup", "a man throws a ball") or climbs one ("a quadruped
robot climbs the stairs") would otherwise come out as two objects standing side by side, or as a
robot floating up with no stairs. `refuse_unsupported` raises a `CommandError` naming the words it
cannot honour and what can be said instead. Intransitive uses stay motions: "a cat climbs up",
"an apple drops", "a balloon lifts off".
"""

from __future__ import annotations

from collections.abc import Sequence

from ...errors import CommandError
from ..lexicon import DETS, NUMBER_WORDS
from ..vocabulary import noun_to_category
from .tokens import detok, is_number

__all__ = ["HANDLING_VERBS", "CLIMBING_VERBS", "refuse_unsupported"]

# verb -> the particle it needs to mean handling ("picks up"), or "" for none
HANDLING_VERBS: dict[str, str] = {
    **dict.fromkeys(("pick", "picks", "picking", "picked"), "up"),
    **dict.fromkeys(("grab", "grabs", "grabbing", "grasp", "grasps", "grasping", "lift", "lifts", "lifting",
                     "carry", "carries", "carrying", "hold", "holds", "holding", "throw", "throws", "throwing",
                     "catch", "catches", "catching", "kick", "kicks", "kicking", "drop", "drops", "dropping",
                     "push", "pushes", "pushing", "place", "places", "placing", "stack", "stacks", "stacking"), ""),
}
CLIMBING_VERBS = frozenset({"climb", "climbs", "climbing", "climbed", "scale", "scales", "scaling"})
_OBJECT_WORDS = frozenset({"stairs", "staircase", "steps", "ladder", "wall", "hill", "slope", "ramp"})
_SAY_INSTEAD = ("say what each object does on its own, e.g. 'a red cup moves up next to a robot' or 'a robot "
                "moves to the red cup'")


def _object_follows(toks: Sequence[str], j: int) -> bool:
    """Whether a noun phrase starts at j ("a red cup", "the stairs", "two balls", "stairs")."""
    if j >= len(toks):
        return False
    w = toks[j]
    return (w in DETS or w in NUMBER_WORDS or is_number(w) or w in _OBJECT_WORDS
            or noun_to_category(w) is not None)


def refuse_unsupported(toks: Sequence[str]) -> None:
    """Raise a `CommandError` for an action on another object in a description.

    Raises:
        CommandError: the message quotes the unsupported words ("picks up a red cup", "climbs the
            stairs") and says what is supported instead.
    """
    for i, w in enumerate(toks):
        j = i + 1
        if w in HANDLING_VERBS:
            particle = HANDLING_VERBS[w]
            if particle:
                if j >= len(toks) or toks[j] != particle:
                    continue
                j += 1
            if _object_follows(toks, j):
                what = detok(list(toks[i:_phrase_end(toks, j)]))
                raise CommandError(f"Could not honour {what!r} in {detok(list(toks))!r}: an object acting on "
                                   f"another (picking up, grasping, carrying, throwing, pushing) is not supported; "
                                   f"objects move on their own paths. Instead, {_SAY_INSTEAD}")
        elif w in CLIMBING_VERBS and _object_follows(toks, j):
            what = detok(list(toks[i:_phrase_end(toks, j)]))
            raise CommandError(f"Could not honour {what!r} in {detok(list(toks))!r}: climbing stairs or other "
                               f"objects is not supported (the scene has no stairs, and objects do not walk on "
                               f"one another); say e.g. 'a quadruped robot walks to the left' or 'a quadruped "
                               f"robot moves up'")


def _phrase_end(toks: Sequence[str], j: int) -> int:
    """End of a short noun phrase at j: up to and including its first noun (at most 4 words)."""
    for k in range(j, min(len(toks), j + 4)):
        if noun_to_category(toks[k]) is not None or toks[k] in _OBJECT_WORDS:
            return k + 1
    return min(len(toks), j + 2)
