"""Descriptions: subjects and their motions read into the parse state (objects, motions, settings)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from ...errors import CommandError
from ..grounding import ground_noun, ground_noun_vocabulary
from ..lexicon import (
    CLAUSE_LEADS,
    COLLECTIVE_NOUNS,
    CONJ,
    DETS,
    EXAMPLES,
    INTENSIFIERS,
    NUMBER_WORDS,
    PLURAL_DEFAULT_COUNT,
    SIZE_WORDS,
    SPATIAL_NOUNS,
    VERBS,
)
from ..plan import MAX_COUNT, CameraSpec, ColorSpec
from ..vocabulary import noun_to_category, singular
from .camera import extract_camera_clauses, read_camera
from .motion import Predicate, combine_directions, merge_motion, merge_pred, path_of
from .nouns import NounPhrase, clause_boundary, parse_np
from .scanner import PhraseScanner
from .tokens import detok, is_number
from .unsupported import refuse_unsupported

__all__ = ["DescriptionReader", "ObjectDraft", "number_agreement"]


@dataclass
class ObjectDraft:
    name: str
    noun: str
    category: str
    color: ColorSpec | None = None
    size: str | None = None
    scale: float = 1.0
    count: int = 1
    grounding: str = "vocabulary"
    similarity: float | None = None
    landmark: bool = False


def number_agreement(subjects: list[NounPhrase], toks: Sequence[str], i: int) -> None:
    """A noun that looks plural is singular when its verb is ("the buss is moving")."""
    w = toks[i]
    singular_verb = w in ("is", "was", "has", "does") or (w in VERBS and w.endswith("s") and w != VERBS[w])
    if singular_verb and len(subjects) == 1 and subjects[0].kind in ("unknown", "category") \
            and subjects[0].count is None and not subjects[0].collective:
        subjects[0].plural = False  # also "the busses is moving" (a typo either way: trust the verb)


def _subjects(toks: list[str], i: int) -> tuple[list[NounPhrase], int]:
    """The subject noun phrases at i ("a ball and a cube", "the dog, the cat") and the index after them."""
    n = len(toks)
    subjects: list[NounPhrase] = []
    while i < n:
        np_ = parse_np(toks, i)
        if np_ is None:
            break
        subjects.append(np_)
        i = np_.end
        if i < n and toks[i] == "'s":
            break
        if i < n and toks[i] in ("and", ",") and i + 1 < n:
            j = i + 1
            if toks[j] == "and":
                j += 1
            nxt = parse_np(toks, j) if j < n else None
            if nxt is not None and toks[j] not in VERBS:
                i = j
                continue
        break
    return subjects, i


def _only_unknown_words(subjects: list[NounPhrase], pred: Predicate) -> bool:
    """Unknown bare words as subjects, and no verb, direction, side, setting or path understood."""
    return bool(subjects) and all(np_.kind == "unknown" and np_.det is None and np_.count is None
                                  for np_ in subjects) and not (pred.verbs or pred.dirs or pred.from_side
                                                                or pred.to_side or pred.settings or pred.path)


def _count_of(np_: NounPhrase) -> int:
    """How many objects a phrase asks for: its number, else PLURAL_DEFAULT_COUNT for a plural or
    collective, else 1."""
    if np_.count is not None:
        return np_.count
    if np_.collective or (np_.plural and np_.kind in ("category", "unknown")):
        return PLURAL_DEFAULT_COUNT
    return 1


def _clause_speed(subjects: list[NounPhrase], pred: Predicate) -> tuple[float | None, str | None]:
    """A clause's speed: its speed words, else a relative factor, else a subject's ("a fast car")."""
    if pred.speed is not None:
        return pred.speed, pred.speed_word
    if pred.factor is not None:
        return pred.factor, "relative"
    for np_ in subjects:
        if np_.speed is not None:
            return np_.speed
    return None, None


class DescriptionReader:
    """Reads description segments into the parse state of `RuleParser` (a mixin of it)."""

    # ---- generate ------------------------------------------------------------------------------------
    def _generate_segment(self, toks: list[str]) -> None:
        toks, cam_spans = extract_camera_clauses(toks)
        refuse_unsupported(toks)
        pending: Predicate | None = None
        i = 0
        n = len(toks)
        any_clause = False
        while i < n:
            while i < n and (toks[i] in CONJ or toks[i] in CLAUSE_LEADS):
                i += 1
            if i >= n:
                break
            subjects, i = _subjects(toks, i)
            pred = Predicate()
            j = PhraseScanner(toks).scan(i, n, pred, boundary=lambda k: clause_boundary(toks, k))
            if j == i and not subjects:
                # nothing readable here: skip a word (it is reported if nothing at all is understood)
                pred.unknown.append(toks[i])
                i += 1
                continue
            if _only_unknown_words(subjects, pred):
                # unknown words with no article and nothing else understood: not a description
                i = max(j, i + 1)
                continue
            if i < n and subjects:
                number_agreement(subjects, toks, i)
            if not subjects and not self.salience and pred.has_motion():
                pending = pred if pending is None else merge_pred(pending, pred)  # "from right to left, a ball ..."
                i = j
                continue
            if pending is not None and subjects:
                pred = merge_pred(pred, pending)
                pending = None
            any_clause = self._apply_clause(subjects, pred, toks) or any_clause
            i = j
        for span in cam_spans:  # after the objects, so that "circles the cat" finds the cat
            self._camera_clause(span, generate=True)
        if not any_clause and not cam_spans and not self.settings:
            raise CommandError(f"Could not understand {detok(toks)!r}: expected a description such as "
                               + EXAMPLES[0] + " or an edit such as " + EXAMPLES[2])

    def _apply_clause(self, subjects: list[NounPhrase], pred: Predicate, toks: list[str]) -> bool:
        """Add a clause's subjects, landmarks and motion to the parse state; False when it says
        nothing about objects or settings."""
        settings = list(pred.settings)
        for np_ in subjects:
            settings.extend(np_.settings)
        objs = self._subject_objects(subjects, settings, toks)
        self.settings.extend(settings)
        if not objs and pred.with_nps and pred.has_motion():
            # "an underwater scene with a fish swimming to the right"
            objs = [self._object_from_np(np_, subject=True) for np_ in pred.with_nps]
            pred.statics = [np_ for np_ in pred.statics if np_ not in pred.with_nps]
        if not objs:
            if not (pred.has_motion() and not settings and subjects == []):
                return bool(settings)
            if not (self.salience and pred.verbs):
                return False
            objs = [self._obj(self.salience[-1])]  # subjectless continuation ("... and bounces")
        self._add_statics(pred)
        for key in ("start", "end", "around"):
            np_ = getattr(pred, key)
            if np_ is not None and np_.kind == "unknown" and np_.head in SPATIAL_NOUNS:
                setattr(pred, key, None)
        if pred.has_motion():
            self._add_motion(objs, subjects, pred, toks)
        else:
            for o in objs:
                self._touch(o.name)
        return True

    def _subject_objects(self, subjects: list[NounPhrase], settings: list[str], toks: list[str]) -> list[ObjectDraft]:
        """The objects the subjects name (settings they name go to `settings`)."""
        objs: list[ObjectDraft] = []
        for np_ in subjects:
            if np_.kind == "setting" and np_.det in ("a", "an") and noun_to_category(np_.head) is not None:
                objs.append(self._object_from_np(np_, subject=True))   # "a desk": a thing, not the table setting
            elif np_.kind == "setting":
                if np_.head == "table" or np_.category:
                    settings.append(np_.category)
            elif np_.kind == "pronoun":
                if not self.salience:
                    raise CommandError(f"Could not tell what {np_.head!r} refers to in {detok(toks)!r}: name the "
                                       f"object first")
                objs.append(self._obj(self.salience[-1]))
            elif np_.kind not in ("viewer", "camera", "generic", "all"):
                objs.append(self._object_from_np(np_, subject=True))
        return objs

    def _add_statics(self, pred: Predicate) -> None:
        """Static objects of a clause ("past a tree", "a dog fetches a ball")."""
        for np_ in pred.statics:
            if np_.kind == "category" or (np_.kind == "unknown" and np_.head not in SPATIAL_NOUNS):
                try:
                    self._object_from_np(np_, subject=False, landmark=True)
                except CommandError:
                    if np_.kind == "category":
                        raise
                    # an incidental place word that is no object ("across the glassy surface"): skip it

    def _add_motion(self, objs: list[ObjectDraft], subjects: list[NounPhrase], pred: Predicate,
                    toks: list[str]) -> None:
        speed, speed_word = _clause_speed(subjects, pred)
        direction = combine_directions(pred, toks)
        path = path_of(pred, direction)
        if path == "stop":
            direction = None
        start = self._landmark(pred.start) if pred.start is not None else None
        end_ = self._landmark(pred.end) if pred.end is not None else None
        around = self._landmark(pred.around) if pred.around is not None else None
        if path == "oscillate" and direction is None and pred.oscillate_axis is not None:
            direction = pred.oscillate_axis
        if path == "bounce" and pred.oscillate:
            direction = None
        if pred.mutual:
            objs = self._meeting_pair(objs, toks)
            if direction is not None or start or end_ or around or path not in ("straight", "bounce", "zigzag"):
                raise CommandError(f"Could not understand {detok(toks)!r}: two objects moving towards each other take "
                                   f"no other direction, landmark or path; say e.g. 'two cars drive towards each other'")
        for k, o in enumerate(objs):
            if pred.mutual:      # the first comes from the left, the second from the right; each heads for the other
                direction, end_ = ((1.0, 0.0, 0.0), objs[1].name) if k == 0 else ((-1.0, 0.0, 0.0), objs[0].name)
            if o.name in (start, end_, around):
                raise CommandError(f"Could not understand {detok(toks)!r}: {o.noun!r} cannot move to or around itself")
            m = {"target": o.name, "path": path, "direction_world": direction,
                 "speed": speed if speed is not None else 1.0, "speed_word": speed_word if speed is not None else None,
                 "start": start, "end": end_, "around": around if path == "circle" else None,
                 "clockwise": pred.clockwise if path == "circle" else None}
            old = self.motions.get(o.name)
            if old is not None:
                m = merge_motion(old, m)
            self.motions[o.name] = m
            self._touch(o.name)

    def _meeting_pair(self, objs: list[ObjectDraft], toks: list[str]) -> list[ObjectDraft]:
        """The two objects of "towards each other": two subjects, or one subject of count 2 made two objects."""
        if len(objs) == 1 and objs[0].count == 2:
            first = objs[0]
            first.count = 1
            names = {o.name for o in self.objects}
            k = 2
            while f"{first.noun}_{k}" in names:
                k += 1
            second = replace(first, name=f"{first.noun}_{k}")
            self.objects.insert(self.objects.index(first) + 1, second)
            return [first, second]
        if len(objs) == 2 and all(o.count == 1 for o in objs):
            return objs
        found = " and ".join(f"{o.count} {o.noun}" for o in objs)
        raise CommandError(f"Could not understand {detok(toks)!r}: 'towards each other' is supported for two objects "
                           f"('two cars', 'a car and a truck'), found {found}")

    def _touch(self, name: str) -> None:
        if name in self.salience:
            self.salience.remove(name)
        self.salience.append(name)

    def _obj(self, name: str) -> ObjectDraft:
        for o in self.objects:
            if o.name == name:
                return o
        raise KeyError(name)

    def _object_from_np(self, np_: NounPhrase, subject: bool, landmark: bool = False) -> ObjectDraft:
        """The object a noun phrase names: one already in the plan ("the ball"), else a new one."""
        g = self._ground(np_)
        noun = singular(np_.head) if (np_.plural or np_.kind == "unknown") else np_.head
        if g.method == "vocabulary":
            noun = g.noun if noun_to_category(np_.head) and noun_to_category(np_.head)[1] else noun
        old = self._coreferent(np_, noun, g.category)
        if old is not None:
            return old
        count = _count_of(np_)
        if count < 1 or count > MAX_COUNT:
            raise CommandError(f"Could not generate {count} {noun}s: the count must be between 1 and {MAX_COUNT}")
        names = {o.name for o in self.objects}
        name = noun
        k = 2
        while name in names:
            name = f"{noun}_{k}"
            k += 1
        o = ObjectDraft(name=name, noun=noun, category=g.category,
                        color=ColorSpec(*np_.color) if np_.color else None, size=np_.size, scale=np_.scale,
                        count=count, grounding=g.method, similarity=g.similarity, landmark=landmark)
        self.objects.append(o)
        return o

    def _coreferent(self, np_: NounPhrase, noun: str, category: str) -> ObjectDraft | None:
        """Coreference: "the ball" (or a bare noun) naming an object already in the plan (its colour,
        when the phrase gives one and the object has none, is set)."""
        if np_.det in ("a", "an", "another") or np_.count is not None or np_.collective:
            return None
        for o in reversed(self.objects):
            if o.noun == noun or (o.category == category and np_.det in ("the", "this", "that")):
                if np_.color is not None and o.color is not None and o.color.name != np_.color[0]:
                    continue
                if np_.color is not None and o.color is None:
                    o.color = ColorSpec(*np_.color)
                return o
        return None

    def _ground(self, np_: NounPhrase):
        if np_.kind == "category":
            hit = ground_noun_vocabulary(np_.head)
            if hit is not None:
                return hit
        head = singular(np_.head) if np_.plural else np_.head
        # unknown nouns are embedded with their descriptive words ("golden retriever", "toy sedan")
        mods = [w for w in np_.words[:-1] if w not in DETS and w not in (",", "'s", "of") and not is_number(w)
                and w not in SIZE_WORDS and w not in INTENSIFIERS and w not in NUMBER_WORDS
                and w not in COLLECTIVE_NOUNS]
        return ground_noun(head, phrase=" ".join(mods[-2:] + [head]) if mods else None)

    def _landmark(self, np_: NounPhrase) -> str:
        if np_.kind == "pronoun":
            if not self.salience:
                raise CommandError("Could not tell what a pronoun refers to: name the object")
            return self.salience[-1]
        o = self._object_from_np(np_, subject=False, landmark=True)
        return o.name

    def _camera_clause(self, toks: list[str], generate: bool) -> CameraSpec:
        cam = read_camera(toks)
        target = None
        if cam.get("target_np") is not None:
            np_ = cam["target_np"]
            if np_.kind == "setting" or np_.head == "table":
                self.settings.append(np_.category if np_.kind == "setting" else "table")
            elif np_.kind in ("category", "unknown", "pronoun") and generate:
                target = self._landmark(np_)  # "the camera orbits it": the last subject
            elif np_.kind in ("category", "unknown"):
                target = np_
        for s in cam.get("settings", []):
            self.settings.append(s)
        spec = CameraSpec(motion=cam["motion"], direction=cam.get("direction"), speed=cam.get("speed", 1.0),
                          speed_word=cam.get("speed_word"), target=target if isinstance(target, str) else None)
        if generate:
            self.camera = spec
        return spec
