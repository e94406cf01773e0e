"""What the clip's prompt says about each labelled object: its category and asked colour.

A fitted scene's objects are named by the clip's mask labels ("mug", "mug_2"); the prompt the
clip came with ("a red mug ... next to a blue mug") names their categories and colours, which
the envs' instructions and the benchmark's edit templates read ("keep the red mug centred",
"delete the blue mug"). Only the prompt is read (its parse; a generated clip carries that parse
in `info["plan"]`), never the generator's scene.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Optional

from ..scene import GeneratedClip, Scene4D

__all__ = ["prompt_objects", "with_prompt_objects"]


def _from_plan(plan: Any) -> dict[str, tuple[str, Optional[tuple]]]:
    out = {}
    for o in plan.get("objects", ()) if isinstance(plan, dict) else ():
        color = o.get("color") or {}
        rgb = color.get("rgb") if isinstance(color, dict) else None
        if o.get("name"):
            out[str(o["name"])] = (str(o.get("category") or o["name"]), tuple(float(c) for c in rgb) if rgb else None)
    return out


def prompt_objects(clip: GeneratedClip) -> dict[str, tuple[str, Optional[tuple]]]:
    """Label -> (category, rgb or None) of the objects the clip's prompt names; {} without a prompt."""
    found = _from_plan(clip.info.get("plan"))
    if found or not clip.prompt:
        return found
    from ..language import parse

    try:
        plan = parse(clip.prompt)
    except ValueError:                      # a prompt the parser does not read: labels stay as they are
        return {}
    return {o.name: (o.category, tuple(o.color.rgb) if o.color is not None else None)
            for o in getattr(plan, "objects", ())}


def with_prompt_objects(scene: Scene4D, clip: GeneratedClip) -> Scene4D:
    """`scene` with each object the prompt names given its category and colour (where it has none)."""
    named = prompt_objects(clip)
    objects = []
    for o in scene.objects:
        category, rgb = named.get(o.name, (o.category, None))
        objects.append(replace(o, category=category, color=o.color if o.color is not None else rgb))
    if tuple(objects) == tuple(scene.objects):
        return scene
    out = scene.derive(None, objects=tuple(objects))
    if hasattr(scene, "_fit_log"):
        out._fit_log = scene._fit_log
    return out
