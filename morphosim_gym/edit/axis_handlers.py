"""Editor handlers of the perturbation-axis edit kinds: (scene, op, selection or None) -> new scene.

`AXIS_HANDLERS` joins the editor's type -> handler table (`editor._HANDLERS`); an op without
targets (light, sky, setting, view, sensor, an insertion with no anchor) gets selection None.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..language.plan import (DelayOp, InsertOp, LightOp, ScaleOp, SensorOp, SettingOp, SkyOp, SwapOp, TextureOp,
                             ViewOp)
from ..scene import Scene4D
from . import axis_ops
from .select import Selection

__all__ = ["AXIS_HANDLERS"]


def _rgb(op: Any) -> tuple[float, float, float] | None:
    return None if op.color is None else tuple(op.color.rgb)


def _scale(scene: Scene4D, op: ScaleOp, sel: Selection) -> Scene4D:
    return axis_ops.scale_objects(scene, sel.mask, op.factor)


def _swap(scene: Scene4D, op: SwapOp, sel: Selection) -> Scene4D:
    return axis_ops.swap_objects(scene, sel.mask, op.category, _rgb(op))


def _insert(scene: Scene4D, op: InsertOp, sel: Selection | None) -> Scene4D:
    anchors = [] if sel is None else list(sel.object_ids)
    return axis_ops.insert_object(scene, anchors, op.category, _rgb(op), op.relation)


_LIGHT: dict[str, Callable[[Scene4D, LightOp], Scene4D]] = {
    "brightness": lambda s, op: axis_ops.light_brightness(s, op.factor),
    "temperature": lambda s, op: axis_ops.light_temperature(s, op.amount),
    "direction": lambda s, op: axis_ops.light_direction(s, op.direction_world),
}


def _light(scene: Scene4D, op: LightOp, sel: None) -> Scene4D:
    return _LIGHT[op.mode](scene, op)


def _sky(scene: Scene4D, op: SkyOp, sel: None) -> Scene4D:
    return axis_ops.set_sky(scene, op.name)


def _texture(scene: Scene4D, op: TextureOp, sel: Selection) -> Scene4D:
    return axis_ops.texture(scene, sel.mask, op.name)


def _setting(scene: Scene4D, op: SettingOp, sel: None) -> Scene4D:
    return axis_ops.set_setting(scene, op.name)


def _view(scene: Scene4D, op: ViewOp, sel: None) -> Scene4D:
    return axis_ops.change_view(scene, op.factor, op.amount)


def _sensor(scene: Scene4D, op: SensorOp, sel: None) -> Scene4D:
    return axis_ops.add_sensor(scene, op.name, op.amount)


def _delay(scene: Scene4D, op: DelayOp, sel: Selection) -> Scene4D:
    return axis_ops.delay(scene, list(sel.object_ids), op.seconds)


AXIS_HANDLERS: dict[type, Callable[[Scene4D, Any, Any], Scene4D]] = {
    ScaleOp: _scale, SwapOp: _swap, InsertOp: _insert, LightOp: _light, SkyOp: _sky, TextureOp: _texture,
    SettingOp: _setting, ViewOp: _view, SensorOp: _sensor, DelayOp: _delay,
}
