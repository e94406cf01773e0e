"""Accuracy of the parser on a labelled corpus: exact-plan and per-field.

    python -m morphosim_gym.language.evaluate tests/language/corpus.jsonl [--json] [--failures N]

Corpus format (JSON lines): ``{"id", "kind", "text", "expect", "scene"?}``. ``expect`` is either
``{"error": true}`` (the parser must raise `CommandError`) or a compact plan:

    {"mode": "generate",
     "objects": [{"category": "ball", "color": "red", "size": "small", "count": 1, "noun": "ball", "name": "ball"}],
     "motions": [{"target": "ball", "path": "bounce", "dir": "left", "speed": 1.0,
                  "start": null, "end": null, "around": null, "clockwise": null}],
     "camera": {"motion": "orbit", "direction": null, "speed": 1.0, "target": null},
     "setting": "ground",
     "edits": [...], "then": [[op, ...], ...]}

Omitted keys take defaults (noun = category, name = noun, count 1, path "straight", speed 1.0,
camera fixed, setting "ground"). Directions are names ("left", "toward", "up+left", "northeast")
compared as unit vectors. An edit op is ``{"op", "targets": [names or nouns], ...}`` with
``color`` (assign), ``add`` + ``amount`` (additive), ``mul`` (multiplicative), ``factor`` / ``speed``
(speed), ``dir`` / ``path`` / ``end`` / ``clockwise`` (redirect), ``camera`` (camera). ``scene`` is a
list of ``[name, category]`` pairs given to the parser as the scene.

A plan is correct ("exact") when its canonical summary equals the label's; per-field accuracy
compares one projection at a time over the items where the field applies.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

from ..errors import CommandError
from .lexicon import DIRECTIONS
from .plan import EditOp, Plan

__all__ = ["load_corpus", "canonical_label", "summarize", "evaluate", "FIELDS", "CorpusScene", "main"]


@dataclass(frozen=True)
class _Obj:
    name: str
    category: str
    id: int
    role: str = "object"


class CorpusScene:
    """A minimal scene for corpus items: objects with name, category, id, role."""

    def __init__(self, pairs: Sequence[Sequence[str]]) -> None:
        bg = {"ground", "water", "road", "sky", "snow", "grass", "sand", "table", "indoor"}
        self.objects = [_Obj(p[0], p[1], i, "background" if (len(p) > 2 and p[2] == "background") or (
            p[1] in bg and p[0] in bg and p[1] != "table") else "object") for i, p in enumerate(pairs)]


def load_corpus(path: str | Path) -> list[dict]:
    """Read a JSON-lines corpus."""
    items = []
    for ln, line in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        try:
            items.append(json.loads(line))
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}:{ln}: not JSON ({exc})") from None
    return items


# -- canonical forms --------------------------------------------------------------------------------------


def _dir_vec(name: Any) -> tuple[float, ...] | None:
    if name is None:
        return None
    if isinstance(name, (list, tuple)):
        v = [float(x) for x in name]
    else:
        v = [0.0, 0.0, 0.0]
        for part in str(name).split("+"):
            d = DIRECTIONS[part]
            v = [a + b for a, b in zip(v, d)]
    n = math.sqrt(sum(c * c for c in v))
    return tuple(round(c / n, 3) + 0.0 for c in v)


def _r(x: Any) -> Any:
    return None if x is None else round(float(x), 3)


def _canon_op(op: dict) -> dict:
    kind = op["op"]
    out: dict = {"op": kind, "targets": list(op.get("targets", []))}
    if kind == "recolor":
        if "color" in op:
            out.update(mode="assign", color=op["color"])
        elif "add" in op:
            out.update(mode="additive", color=op["add"], amount=_r(op.get("amount", 0.3)))
        else:
            out.update(mode="multiplicative", factor=_r(op["mul"]))
    elif kind == "redirect":
        out.update(dir=_dir_vec(op.get("dir")), path=op.get("path"), end=op.get("end"), around=op.get("around"),
                   clockwise=op.get("clockwise"))
    elif kind == "speed":
        out.update(factor=_r(op.get("factor")), speed=_r(op.get("speed")))
    elif kind == "camera":
        out["camera"] = _canon_camera(op.get("camera", {}))
    return out


def _canon_camera(c: dict | None) -> dict:
    c = c or {}
    motion = c.get("motion", "fixed")
    return {"motion": motion, "direction": c.get("direction"), "speed": _r(c.get("speed", 1.0)),
            "target": c.get("target")}


def canonical_label(expect: dict) -> dict:
    """Fill a label's defaults into the canonical summary form."""
    if expect.get("error"):
        return {"error": True}
    mode = expect.get("mode") or ("generate" if "objects" in expect else "edit")
    out: dict = {"mode": mode}
    if mode == "generate":
        objs = []
        for o in expect.get("objects", []):
            noun = o.get("noun", o["category"])
            objs.append({"name": o.get("name", noun), "noun": noun, "category": o["category"],
                         "color": o.get("color"), "size": o.get("size"), "count": o.get("count", 1)})
        out["objects"] = sorted(objs, key=lambda d: d["name"])
        mots = []
        for m in expect.get("motions", []):
            mots.append({"target": m["target"], "path": m.get("path", "straight"), "dir": _dir_vec(m.get("dir")),
                         "speed": _r(m.get("speed", 1.0)), "start": m.get("start"), "end": m.get("end"),
                         "around": m.get("around"), "clockwise": m.get("clockwise")})
        out["motions"] = sorted(mots, key=lambda d: d["target"])
        out["camera"] = _canon_camera(expect.get("camera"))
        out["setting"] = expect.get("setting", "ground")
        out["edits"] = []
    else:
        out["edits"] = [_canon_op(op) for op in expect.get("edits", [])]
    out["then"] = [[_canon_op(op) for op in ops] for ops in expect.get("then", [])]
    return out


def _op_summary(e: EditOp) -> dict:
    targets: list[str] = []
    for t in e.targets:
        targets.extend(t.objects if t.objects else [t.noun])
    d: dict = {"op": e.op, "targets": targets}
    if e.op == "recolor":
        if e.mode == "assign":
            d.update(color=e.color.name)
        elif e.mode == "additive":
            rgb = e.color.rgb if e.color else (1.0, 1.0, 1.0)
            n2 = sum(c * c for c in rgb) or 1.0
            d.update(add=e.color.name if e.color else None,
                     amount=sum(a * b for a, b in zip(e.delta, rgb)) / n2)
        else:
            d.update(mul=e.factor_rgb[0])
    elif e.op == "redirect":
        d.update(dir=list(e.direction_world) if e.direction_world else None, path=e.path, end=e.end,
                 around=e.around, clockwise=e.clockwise)
    elif e.op == "speed":
        d.update(factor=e.factor, speed=e.speed)
    elif e.op == "camera":
        d["camera"] = {"motion": e.camera.motion, "direction": e.camera.direction, "speed": e.camera.speed,
                       "target": e.camera.target}
    return _canon_op(d)


def summarize(plan: Plan) -> dict:
    """The canonical summary of a plan (same form as `canonical_label`)."""
    out: dict = {"mode": plan.mode}
    if plan.mode == "generate":
        out["objects"] = sorted(({"name": o.name, "noun": o.noun, "category": o.category,
                                  "color": o.color.name if o.color else None, "size": o.size, "count": o.count}
                                 for o in plan.objects), key=lambda d: d["name"])
        out["motions"] = sorted(({"target": m.target, "path": m.path, "dir": _dir_vec(m.direction_world),
                                  "speed": _r(m.speed), "start": m.start, "end": m.end, "around": m.around,
                                  "clockwise": m.clockwise} for m in plan.motions), key=lambda d: d["target"])
        c = plan.camera
        out["camera"] = {"motion": c.motion, "direction": c.direction, "speed": _r(c.speed), "target": c.target}
        out["setting"] = plan.setting
        out["edits"] = []
    else:
        out["edits"] = [_op_summary(e) for e in plan.edits]
    out["then"] = [[_op_summary(e) for e in p.edits] for p in plan.then]
    return out


# -- fields -------------------------------------------------------------------------------------------------


def _proj(key: str, sub: str | None = None) -> Callable[[dict], Any]:
    def f(s: dict) -> Any:
        if "error" in s:
            return "error"
        v = s.get(key)
        if sub is None or v is None:
            return v
        if isinstance(v, list):
            return [x.get(sub) for x in v]
        return v.get(sub)
    return f


def _all_ops(s: dict) -> list[dict]:
    if "error" in s:
        return []
    return list(s.get("edits", [])) + [op for ops in s.get("then", []) for op in ops]


def _ops_proj(keys: Sequence[str] | None) -> Callable[[dict], Any]:
    def f(s: dict) -> Any:
        if "error" in s:
            return "error"
        ops = _all_ops(s)
        if keys is None:
            return [{k: v for k, v in op.items() if k not in ("op", "targets")} for op in ops]
        return [[op.get(k) for k in keys] for op in ops]
    return f


# name -> (projection, applies-to predicate on the label)
FIELDS: dict[str, tuple[Callable[[dict], Any], Callable[[dict], bool]]] = {
    "error_or_plan": (lambda s: "error" in s, lambda lab: True),
    "mode": (_proj("mode"), lambda lab: "error" not in lab),
    "objects.category": (_proj("objects", "category"), lambda lab: lab.get("mode") == "generate"),
    "objects.color": (_proj("objects", "color"), lambda lab: lab.get("mode") == "generate"),
    "objects.size": (_proj("objects", "size"), lambda lab: lab.get("mode") == "generate"),
    "objects.count": (_proj("objects", "count"), lambda lab: lab.get("mode") == "generate"),
    "objects.noun": (_proj("objects", "noun"), lambda lab: lab.get("mode") == "generate"),
    "motions.path": (_proj("motions", "path"), lambda lab: lab.get("mode") == "generate"),
    "motions.direction": (_proj("motions", "dir"), lambda lab: lab.get("mode") == "generate"),
    "motions.speed": (_proj("motions", "speed"), lambda lab: lab.get("mode") == "generate"),
    "motions.landmarks": (lambda s: "error" if "error" in s else [(m["start"], m["end"], m["around"]) for m in
                                                                  s.get("motions", [])],
                          lambda lab: lab.get("mode") == "generate"),
    "motions.clockwise": (_proj("motions", "clockwise"), lambda lab: lab.get("mode") == "generate"),
    "camera": (_proj("camera"), lambda lab: lab.get("mode") == "generate"),
    "setting": (_proj("setting"), lambda lab: lab.get("mode") == "generate"),
    "edits.ops": (_ops_proj(("op",)), lambda lab: bool(_all_ops(lab))),
    "edits.targets": (_ops_proj(("targets",)), lambda lab: bool(_all_ops(lab))),
    "edits.params": (_ops_proj(None), lambda lab: bool(_all_ops(lab))),
    "then.structure": (lambda s: "error" if "error" in s else [len(x) for x in s.get("then", [])],
                       lambda lab: "error" not in lab),
}


def evaluate(items: Sequence[dict], parse: Callable[..., Plan] | None = None) -> dict:
    """Parse every corpus item and compare with its label.

    Returns a dict with ``n``, ``exact`` (fraction), ``fields`` {name: (correct, applicable)},
    ``by_kind`` {kind: (correct, n)}, ``failures`` (list of dicts) and ``seconds``.
    """
    if parse is None:
        from .api import parse as parse_
        parse = parse_
    correct = 0
    fields = {k: [0, 0] for k in FIELDS}
    by_kind: dict[str, list[int]] = {}
    failures = []
    t0 = time.perf_counter()
    for it in items:
        label = canonical_label(it["expect"])
        scene = CorpusScene(it["scene"]) if it.get("scene") else None
        try:
            got = summarize(parse(it["text"], scene))
        except CommandError as exc:
            got = {"error": True, "message": str(exc)}
        cmp_got = {k: v for k, v in got.items() if k != "message"}
        ok = cmp_got == label
        correct += ok
        k = it.get("kind", "other")
        by_kind.setdefault(k, [0, 0])
        by_kind[k][0] += ok
        by_kind[k][1] += 1
        for name, (proj, applies) in FIELDS.items():
            if applies(label):
                fields[name][1] += 1
                fields[name][0] += proj(cmp_got) == proj(label)
        if not ok:
            failures.append({"id": it.get("id"), "text": it["text"], "expected": label, "got": got})
    n = len(items)
    return {"n": n, "exact": correct / n if n else 0.0, "correct": correct,
            "fields": {k: tuple(v) for k, v in fields.items()}, "by_kind": {k: tuple(v) for k, v in by_kind.items()},
            "failures": failures, "seconds": time.perf_counter() - t0}


def format_report(rep: dict) -> str:
    """A plain-text table of a report from `evaluate`."""
    lines = [f"corpus: {rep['n']} commands, exact-plan accuracy {rep['exact'] * 100:.1f}% "
             f"({rep['correct']}/{rep['n']})", "", f"{'field':<22}{'correct':>9}{'of':>6}{'accuracy':>11}"]
    for k, (c, n) in rep["fields"].items():
        lines.append(f"{k:<22}{c:>9}{n:>6}{(c / n * 100 if n else 100):>10.1f}%")
    lines += ["", f"{'kind':<22}{'correct':>9}{'of':>6}{'accuracy':>11}"]
    for k, (c, n) in sorted(rep["by_kind"].items()):
        lines.append(f"{k:<22}{c:>9}{n:>6}{c / n * 100:>10.1f}%")
    return "\n".join(lines)


def _diff(a: Any, b: Any, path: str = "") -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            out += _diff(a.get(k), b.get(k), f"{path}.{k}")
        return out
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        out = []
        for i, (x, y) in enumerate(zip(a, b)):
            out += _diff(x, y, f"{path}[{i}]")
        return out
    return [] if a == b else [f"{path or '.'}: expected {a!r}, got {b!r}"]


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m morphosim_gym.language.evaluate", description=__doc__.split("\n")[0])
    ap.add_argument("corpus", nargs="?", default="tests/language/corpus.jsonl")
    ap.add_argument("--json", action="store_true", help="print the report as JSON")
    ap.add_argument("--failures", type=int, default=20, help="show at most this many failures (default 20)")
    args = ap.parse_args(argv)
    rep = evaluate(load_corpus(args.corpus))
    if args.json:
        print(json.dumps({k: v for k, v in rep.items()}, indent=2, default=str))
        return 0
    print(format_report(rep))
    if rep["failures"] and args.failures:
        print(f"\nfailures ({len(rep['failures'])}):")
        for f in rep["failures"][:args.failures]:
            exp = f["expected"]
            got = {k: v for k, v in f["got"].items() if k != "message"}
            why = "; ".join(_diff(exp, got)) if "error" not in got else f"CommandError: {f['got']['message']}"
            print(f"- [{f['id']}] {f['text']!r}\n    {why}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
