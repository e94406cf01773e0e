"""Rule-based command parser (the offline default): text -> `Plan`.

Modules, in reading order: `tokens` (tokenize, word tests), `nouns` (noun phrases), `motion`
(motion phrases, the phrase scanner), `camera` (camera clauses), `segments` (split and classify),
`describe` (descriptions -> objects and motions), `edits` (edit segments -> op drafts), `targets`
(drafts -> `EditOp`s), `parser` (`parse_rules`). Word lists live in `..lexicon`.

How a command is read
---------------------
1. Normalise and tokenise (lower case, hyphens, possessives, "2x" -> "2 times"), repair typos one
   edit away from a parser word (never a real English word: "bull" stays "bull").
2. Split into segments at sentence ends and at "then" / "after that" / "afterwards" / "finally".
3. A segment is an *edit* when it starts (after "please", "now", "can you"...) with an edit verb
   ("make the bus yellow", "delete the ball", "reverse its motion", "pan left"), or has the form
   "X should/must/is now ...", or continues a description without a subject ("... then stops").
   Otherwise it is a *generate* description: subject noun phrases, their verb, direction and path
   phrases, landmarks, a setting, and a camera clause ("while the camera circles the table").
   Consecutive generate segments merge into one generate plan; edits after it go to `plan.then`
   (one edit plan per segment). A description after an edit is an error.
4. Nouns: vocabulary first, else embedding grounding (`grounding.py`).

Decisions worth knowing
-----------------------
- Objects: one `ObjectSpec` per noun phrase, `count` for plurals ("two balls": count 2; a plural
  without number or a collective "a herd of cows": count 3). "the X" naming an object already in
  the plan refers to it; "a X" adds a new one (named "X_2"...).
- Landmarks: "to/towards/into/onto the X" -> motion end, "from the X" -> start, "around the X" ->
  circle centre; "past/near/next to/with ... the X" adds a static object. A landmark that is not
  yet an object of the plan is added as a static object (no motion); the generator places it.
- Settings: the first setting word (water, road, tabletop, snow, grass, sky, sand, room...) in the
  text; otherwise the habitat of the first object that has one (fish -> water, car -> road);
  otherwise "ground". "table" after a locative preposition ("on/across the table") or as what the
  camera circles is the tabletop setting, not an object; as a subject, with a colour/count, or as a
  motion's start/end it is an object.
- Pronouns "it/its/them/they" refer to the most recent subject or edit target (landmarks only when
  nothing else was named). With a scene and no antecedent, "it" is the scene's only non-background
  object, else an error.
- Edits without a scene keep their targets as written with a grounded category (``objects`` empty),
  unless ``require_scene=True``; a pronoun with nothing to refer to is always an error.
"""


from ..lexicon import EDIT_VERBS, EXAMPLES
from .parser import MAX_TEXT_CHARS, parse_rules
from .tokens import tokenize

__all__ = ["EDIT_VERBS", "EXAMPLES", "MAX_TEXT_CHARS", "parse_rules", "tokenize"]
