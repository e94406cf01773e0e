"""The rule-based parser: segments -> descriptions and edits -> one `Plan`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ...errors import CommandError
from ..grounding import SceneItem, scene_items
from ...colors import is_color_word
from .. import wordnet
from ..lexicon import AUX, COMPOUNDS, DETS, EXAMPLES, INTENSIFIERS, NUMBER_WORDS, SIZE_WORDS, VERBS, correct_typo
from ..plan import CameraSpec, EditOp, MotionSpec, ObjectSpec, Plan
from ..sequence import motion_stages
from ..vocabulary import CATEGORIES, DEFAULT_SETTING
from .describe import DescriptionReader, ObjectDraft
from .nouns import compound_noun
from .segments import camera_decl_to_edit, classify, split_segments
from .targets import TargetResolver
from .tokens import detok, is_number, known_word, tokenize

__all__ = ["MAX_TEXT_CHARS", "RuleParser", "parse_rules"]


MAX_TEXT_CHARS = 2000


class RuleParser(DescriptionReader, TargetResolver):
    """The parse state of one command (objects, motions, camera, settings, salience) and its reading."""

    def __init__(self, text: str, scene: Any = None, require_scene: bool = False) -> None:
        self.text = text
        self.scene = scene
        self.require_scene = require_scene
        self.items: list[SceneItem] | None = scene_items(scene) if scene is not None else None
        self.objects: list[ObjectDraft] = []
        self.motions: dict[str, dict] = {}
        self.camera: CameraSpec | None = None
        self.settings: list[str] = []
        self.salience: list[str] = []  # object names, most recent last
        self.scene_salience: list[list[SceneItem]] = []
        self._last_ground: dict[str, str] = {}  # edit target noun -> grounded category (no scene)
        self.generated = False

    # ---- entry -------------------------------------------------------------------------------------
    def parse(self) -> Plan:
        toks = tokenize(self.text)
        toks = [w if _in_compound_noun(toks, k) or _visible_noun_slot(toks, k)
                else self._fix_typo(w, toks[k + 1] if k + 1 < len(toks) else None) for k, w in enumerate(toks)]
        segments = split_segments(toks)
        if not segments:
            raise CommandError(f"Could not understand {self.text!r}: no words found. Try e.g. " + ", ".join(EXAMPLES))
        edits: list[tuple[str, list[EditOp]]] = []
        for seg in segments:
            kind, seg2 = classify(seg, after_generate=self.generated and not edits)
            if kind == "camera":
                kind = "generate" if (self.generated and not edits) else "edit"
                if kind == "edit":
                    seg2 = camera_decl_to_edit(seg2)
            if kind == "generate":
                if edits:
                    raise CommandError(f"Could not understand {' '.join(seg)!r} after an edit: describe the scene "
                                       f"first, then the edits (e.g. 'a ball rolls left; then make it blue')")
                self._generate_segment(seg2)
                self.generated = True
            else:
                ops = self._edit_segment(seg2)
                edits.append((detok(seg), ops))
        return self._build(edits)

    def _fix_typo(self, w: str, nxt: str | None = None) -> str:
        if not w.isalpha() or len(w) < 4 or known_word(w):
            return w
        fixed = correct_typo(w)
        if fixed in VERBS and (nxt in VERBS or nxt in AUX):
            return w   # an unknown word before a verb is the subject's noun ("a go kart moves"), not a verb typo
        return COMPOUNDS.get(fixed, fixed) if fixed is not None else w

    # ---- assemble -----------------------------------------------------------------------------------
    def _build(self, edits: list[tuple[str, list[EditOp]]]) -> Plan:
        then = tuple(Plan(mode="edit", text=text, edits=tuple(ops)) for text, ops in edits)
        if not self.generated:
            if not then:
                raise CommandError(f"Could not understand {self.text!r}. Try e.g. " + ", ".join(EXAMPLES))
            head = then[0]
            return Plan(mode="edit", text=self.text, edits=head.edits, then=then[1:])
        objects = tuple(ObjectSpec(name=o.name, noun=o.noun, category=o.category, color=o.color, size=o.size,
                                   scale=o.scale, count=o.count, grounding=o.grounding, similarity=o.similarity)
                        for o in self.objects)
        motions = tuple(MotionSpec(**self.motions[o.name]) for o in self.objects if o.name in self.motions)
        if self.settings:
            setting, source = self.settings[0], "text"
        else:
            setting, source = DEFAULT_SETTING, "default"
            for o in self.objects:
                h = CATEGORIES[o.category].habitat
                if h is not None:
                    setting, source = h, "inferred"
                    break
        if not objects and source != "text":
            raise CommandError(f"Could not understand {self.text!r}: no object to generate. Try e.g. " + EXAMPLES[0])
        plan = Plan(mode="generate", text=self.text, objects=objects, motions=motions,
                    camera=self.camera or CameraSpec(), setting=setting, setting_source=source, then=then)
        motion_stages(plan)        # a second stage ("... then stops") must continue a motion: refused here if not
        return plan


def _in_compound_noun(toks: Sequence[str], k: int) -> bool:
    """Whether word k and a neighbour form a compound noun WordNet knows ("frying pan", "go kart"):
    then it is no typo of a parser word ("flying", "dart")."""
    return any(compound_noun(*toks[j:j + 2]) for j in (k - 1, k) if j >= 0 and j + 1 < len(toks))


def _visible_noun_slot(toks: Sequence[str], k: int) -> bool:
    """Whether word k is a thing WordNet knows where a noun stands, after a determiner or a number and
    any colour or size words ("a freezer", "two red mopeds"): then it is no typo of a parser word
    ("freeze", "moved"); a word elsewhere still is ("make the cube bleu")."""
    w = toks[k]
    if not w.isalpha() or len(w) < 4 or known_word(w) or not wordnet.is_visible_noun(w):
        return False
    j = k - 1
    while j >= 0 and (is_color_word(toks[j]) or toks[j] in SIZE_WORDS or toks[j] in INTENSIFIERS):
        j -= 1
    return j >= 0 and (toks[j] in DETS or is_number(toks[j]) or toks[j] in NUMBER_WORDS)


def parse_rules(text: str, scene: Any = None, require_scene: bool = False) -> Plan:
    """Parse a command with the rule-based parser.

    Args:
        text: the command.
        scene: optional scene (duck-typed: ``.objects`` with ``.name``/``.category``) that edits
            refer to.
        require_scene: raise when an edit has no scene (and no generated plan) to apply to.

    Raises:
        CommandError: the text is empty, not understood, contradictory, or refers to things that
            are not there; the message says what was not understood and what would be.
    """
    if not isinstance(text, str):
        raise CommandError(f"Expected the command as a string, found {type(text).__name__}")
    if not text.strip():
        raise CommandError("Could not understand an empty command. Try e.g. " + ", ".join(EXAMPLES))
    if len(text) > MAX_TEXT_CHARS:
        raise CommandError(f"Could not parse a command of {len(text)} characters: at most {MAX_TEXT_CHARS}")
    return RuleParser(text, scene, require_scene).parse()
