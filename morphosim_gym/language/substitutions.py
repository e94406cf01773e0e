"""Substitutions: what a plan uses in place of what the text asked for, never in silence.

A plan substitutes when it

- grounds a noun outside the vocabulary to the nearest thing it has ("sedan" -> car, by embedding;
  "teapot" -> an asset): kind "noun", with the similarity;
- stands in for a noun nothing shows by a thing of the same kind ("kangaroo" -> a deer, both mammals;
  grounding level "kind", see `grounding.py`): kind "stand-in", with the similarity;
- repairs a misspelt word to a parser word one edit away ("bleu" -> blue, "roling" -> rolling):
  kind "colour" when the repair is a colour, "motion" when it is a motion verb, else "word".

`plan_substitutions(plan)` lists them; `describe` gives the one line people read ("noun 'kangaroo'
is not in the library: using duck (similarity 0.59)"). How they surface:

- `SubstitutionWarning` (a `UserWarning`) from `MorphoSim.parse`, and so from `generate`,
  `generate_clip`, env creation and every CLI command that makes scenes; the CLI prints each as one
  line, "morphosim <command>: note: ...", on stderr;
- the scene's `provenance.substitutions` ((asked, used, similarity) triples; `morphosim info` shows them);
- the grounding level "exact" turns them into a `CommandError` naming each: `parse(text,
  grounding="exact")`, `SimConfig(grounding="exact")` / `MorphoSim(grounding="exact")` (every parse
  of the pipeline, env scenes included), `$MORPHOSIM_GROUNDING=exact`, and `--grounding exact` on
  `morphosim parse` / `generate` / `view` / `bench`. The old spellings `strict=True` and `--strict`
  still mean "exact" (deprecated aliases).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from ..colors import is_color_word
from ..errors import CommandError

__all__ = ["Substitution", "SubstitutionWarning", "plan_substitutions", "describe", "check_strict", "warn"]


class SubstitutionWarning(UserWarning):
    """A plan uses something other than what its text asked for (see `plan_substitutions`)."""


@dataclass(frozen=True)
class Substitution:
    """`asked` (the words as written) was replaced by `used`; `similarity` for embedding groundings."""

    kind: str
    asked: str
    used: str
    similarity: float | None = None

    def as_triple(self) -> tuple[str, str, float | None]:
        """The (asked, used, similarity) triple scenes record in their provenance."""
        return (self.asked, self.used, self.similarity)


def _typo_repairs(text: str) -> list[Substitution]:
    from .lexicon import VERBS, correct_typo
    from .rules.tokens import known_word, tokenize

    out = []
    for w in tokenize(text):
        if not w.isalpha() or len(w) < 4 or known_word(w):
            continue
        fixed = correct_typo(w)
        if fixed is None or fixed == w or _inflection(w, fixed):
            continue
        kind = "colour" if is_color_word(fixed) else "motion" if fixed in VERBS else "word"
        out.append(Substitution(kind, w, fixed))
    return out


def _inflection(a: str, b: str) -> bool:
    """Whether two words differ only by an ending ("reverses" / "reverse"): the same word, not a substitute."""
    short, long_ = sorted((a, b), key=len)
    return long_.startswith(short) and long_[len(short):] in ("s", "es", "d", "ed")


def _plans(plan: Any) -> Iterable[Any]:
    yield plan
    yield from getattr(plan, "then", ())


def plan_substitutions(plan: Any) -> tuple[Substitution, ...]:
    """Every substitution of a plan (its follow-ups included), in the order of the text."""
    subs: list[Substitution] = list(_typo_repairs(plan.text))
    for p in _plans(plan):
        for o in getattr(p, "objects", ()):
            grounding = getattr(o, "grounding", None)
            if grounding in ("embedding", "open", "kind"):
                subs.append(Substitution("stand-in" if grounding == "kind" else "noun", o.noun, o.category,
                                         o.similarity))
    seen, out = set(), []
    for s in subs:
        if s not in seen:
            seen.add(s)
            out.append(s)
    return tuple(out)


def describe(sub: Substitution) -> str:
    """One line a person reads."""
    sim = f" (similarity {sub.similarity:.2f})" if sub.similarity is not None else ""
    if sub.kind == "noun":
        return f"noun {sub.asked!r} is not in the library: using {sub.used}{sim}"
    if sub.kind == "stand-in":
        return f"noun {sub.asked!r} is not in the library: using {sub.used}, a stand-in of the same kind{sim}"
    return f"{sub.kind} {sub.asked!r} read as {sub.used!r}"


def check_strict(plan: Any) -> None:
    """Raise a `CommandError` naming every substitution of the plan (grounding level "exact", the old strict mode)."""
    subs = plan_substitutions(plan)
    if subs:
        raise CommandError(f"Could not honour {plan.text!r} exactly (grounding 'exact', formerly strict): "
                           + "; ".join(describe(s) for s in subs)
                           + ". Use words the library has, or another grounding level to accept the substitutes")


def warn(plan: Any, stacklevel: int = 3) -> tuple[Substitution, ...]:
    """Issue one `SubstitutionWarning` per substitution of the plan; returns them."""
    subs = plan_substitutions(plan)
    for s in subs:
        warnings.warn(describe(s), SubstitutionWarning, stacklevel=stacklevel)
    return subs
