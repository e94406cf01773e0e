"""The object library: one builder per category, made of shaped, textured primitives.

Each builder returns parts in the object's frame (x forward, y left, z up, resting on
z = 0) at a nominal real-world size in metres. `CATEGORY_SPECS` holds, per category,
its default colour, how it moves (on the ground, in the air, swimming, floating, or
fixed), the setting it usually appears in, and its Gaussian budget.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..scene.parts import Part, Texture, euler

__all__ = ["CategorySpec", "CATEGORY_SPECS", "SHAPE_SPECS", "build_parts", "category_names"]

DARK = (0.08, 0.08, 0.09)
TIRE = (0.07, 0.07, 0.08)
GLASS = ("mix", (0.35, 0.45, 0.55), 0.55)   # windows: the body colour tinted towards blue-grey
SKIN = (0.87, 0.68, 0.55)
WOOD = (0.55, 0.36, 0.2)
METAL = (0.62, 0.64, 0.66)
LEAF = (0.18, 0.5, 0.16)
NOISE = Texture("noise", scale=6.0, amount=0.06)


@dataclass(frozen=True)
class CategorySpec:
    """How a category looks and behaves."""

    name: str
    build: Callable[[], list[Part]]
    color: tuple[float, float, float]
    mobility: str          # "ground", "air", "swim", "float", "fixed"
    setting: str           # the setting it usually appears in
    budget: int = 2400
    rolls: bool = False    # rolls along the ground when it moves (balls)


def _wheel(x: float, y: float, r: float, w: float) -> Part:
    return Part("cylinder", dict(radius=r, height=w), (x, y + w / 2 if y > 0 else y - w / 2, r),
                euler(roll=90 if y > 0 else -90), TIRE, density=0.7)


def _wheels(length: float, width: float, r: float, w: float, inset: float = 0.18) -> list[Part]:
    xs = (length / 2 - inset * length, -length / 2 + inset * length)
    return [_wheel(x, s * (width / 2 - 0.01), r, w) for x in xs for s in (1, -1)]


# --------------------------------------------------------------- vehicles
def bus() -> list[Part]:
    L, W, H = 6.0, 1.9, 2.3
    body = Part("box", dict(size=(L, W, H - 0.4)), (0, 0, 0.4 + (H - 0.4) / 2), color="primary", textures=[NOISE])
    windows = [Part("box", dict(size=(L * 0.82, 0.02, 0.55), faces="yY"), (-0.1, 0, 1.75), color=GLASS, density=1.3),
               Part("box", dict(size=(0.02, W * 0.85, 0.7), faces="X"), (L / 2 + 0.005, 0, 1.7), color=GLASS)]
    stripe = Part("box", dict(size=(L * 1.001, W * 1.004, 0.12), faces="xXyY"), (0, 0, 1.25), color=("primary", 0.7))
    return [body, stripe, *windows, *_wheels(L, W, 0.42, 0.3, 0.16)]


def car() -> list[Part]:
    L, W = 3.2, 1.5
    body = Part("box", dict(size=(L, W, 0.55)), (0, 0, 0.62), textures=[NOISE])
    cabin = Part("box", dict(size=(L * 0.5, W * 0.88, 0.42), faces="xXyYZ"), (-0.15, 0, 1.1), textures=[NOISE])
    glass = Part("box", dict(size=(L * 0.48, W * 0.9, 0.3), faces="xXyY"), (-0.15, 0, 1.1), color=GLASS, density=0.8)
    return [body, cabin, glass, *_wheels(L, W, 0.32, 0.22, 0.2)]


def truck() -> list[Part]:
    L, W = 5.0, 2.0
    cab = Part("box", dict(size=(1.3, W, 1.6)), (L / 2 - 0.65, 0, 1.3), textures=[NOISE])
    glass = Part("box", dict(size=(0.02, W * 0.85, 0.6), faces="X"), (L / 2 + 0.005, 0, 1.75), color=GLASS)
    cargo = Part("box", dict(size=(L - 1.4, W, 2.0)), (-0.7, 0, 1.5), color=("primary", 0.85), textures=[NOISE])
    return [cab, glass, cargo, *_wheels(L, W, 0.45, 0.3, 0.14)]


def train() -> list[Part]:
    L, W, H = 8.0, 2.0, 2.4
    body = Part("box", dict(size=(L, W, H)), (0, 0, 0.5 + H / 2), textures=[NOISE])
    nose = Part("ellipsoid", dict(radii=(1.0, W / 2, H / 2), z_min=-1.0), (L / 2, 0, 0.5 + H / 2), textures=[NOISE])
    windows = Part("box", dict(size=(L * 0.9, W * 1.01, 0.5), faces="yY"), (0, 0, 2.1), color=GLASS, density=1.2)
    stripe = Part("box", dict(size=(L, W * 1.005, 0.15), faces="yY"), (0, 0, 1.3), color=(0.95, 0.95, 0.95))
    bogies = [Part("box", dict(size=(1.6, W * 0.8, 0.45)), (x, 0, 0.28), color=DARK) for x in (-L / 3, L / 3)]
    return [body, nose, windows, stripe, *bogies]


def motorcycle() -> list[Part]:
    frame = Part("capsule", dict(radius=0.16, length=0.9), (0.0, 0, 0.72), euler(pitch=-8), textures=[NOISE])
    tank = Part("ellipsoid", dict(radii=(0.32, 0.18, 0.14)), (0.2, 0, 0.9), textures=[NOISE])
    seat = Part("box", dict(size=(0.5, 0.26, 0.08)), (-0.3, 0, 0.9), color=DARK)
    bars = Part("cylinder", dict(radius=0.025, height=0.6, caps=""), (0.55, 0.3, 1.05), euler(roll=90), color=METAL)
    wheels = [Part("torus", dict(major=0.28, minor=0.08), (x, 0, 0.36), euler(roll=90), TIRE) for x in (0.62, -0.62)]
    return [frame, tank, seat, bars, *wheels]


def bicycle() -> list[Part]:
    wheels = [Part("torus", dict(major=0.33, minor=0.03), (x, 0, 0.36), euler(roll=90), TIRE) for x in (0.55, -0.55)]
    tubes = [Part("cylinder", dict(radius=0.03, height=0.75, caps=""), (-0.45, 0, 0.36), euler(pitch=60)),
             Part("cylinder", dict(radius=0.03, height=0.6, caps=""), (0.5, 0, 0.36), euler(pitch=-20)),
             Part("cylinder", dict(radius=0.03, height=0.9, caps=""), (-0.1, 0, 0.8), euler(pitch=90)),
             Part("cylinder", dict(radius=0.03, height=0.55, caps=""), (-0.1, 0, 0.38), euler(pitch=-30))]
    seat = Part("box", dict(size=(0.22, 0.1, 0.05)), (-0.15, 0, 0.98), color=DARK)
    bars = Part("cylinder", dict(radius=0.02, height=0.5, caps=""), (0.35, 0.25, 1.0), euler(roll=90), color=METAL)
    return [*wheels, *tubes, seat, bars]


def boat() -> list[Part]:
    hull = Part("ellipsoid", dict(radii=(1.6, 0.65, 0.5), z_min=0.0), (0, 0, 0.5), euler(roll=180), textures=[NOISE])
    band = Part("ellipsoid", dict(radii=(1.62, 0.66, 0.12), z_min=0.0), (0, 0, 0.5), euler(roll=180),
                color=("primary", 0.55))
    deck = Part("ellipsoid", dict(radii=(1.55, 0.62, 0.04)), (0, 0, 0.5), color=WOOD,
                textures=[Texture("stripes", (0.45, 0.28, 0.15), 8.0, axis=1)])
    cabin = Part("box", dict(size=(0.8, 0.7, 0.45)), (-0.2, 0, 0.78), color=(0.95, 0.95, 0.93))
    cabin_glass = Part("box", dict(size=(0.6, 0.72, 0.15), faces="yY"), (-0.2, 0, 0.85), color=(0.35, 0.45, 0.55))
    mast = Part("cylinder", dict(radius=0.03, height=1.6), (0.3, 0, 0.5), color=METAL)
    return [hull, band, deck, cabin, cabin_glass, mast]


def airplane() -> list[Part]:
    fus = Part("capsule", dict(radius=0.35, length=4.0), (0, 0, 0.6), textures=[NOISE])
    wing = Part("box", dict(size=(1.0, 5.5, 0.08)), (0.2, 0, 0.5), color=("primary", 0.9))
    tail = Part("box", dict(size=(0.6, 1.8, 0.06)), (-2.1, 0, 0.7), color=("primary", 0.9))
    fin = Part("box", dict(size=(0.7, 0.06, 0.9)), (-2.1, 0, 1.1), color=("primary", 0.85))
    windows = Part("box", dict(size=(3.0, 0.71, 0.12), faces="yY"), (0.2, 0, 0.75), color=GLASS)
    return [fus, wing, tail, fin, windows]


# ---------------------------------------------------------------- animals
def _legs(xs, ys, height, radius, color="primary", nodes=None) -> list[Part]:
    out = []
    i = 0
    for x in xs:
        for y in ys:
            node = nodes[i] if nodes else "body"
            out.append(Part("cylinder", dict(radius=radius, height=height), (x, y, 0), color=color, node=node,
                            textures=[NOISE]))
            i += 1
    return out


def sheep() -> list[Part]:
    fleece = Texture("noise", scale=28.0, amount=0.16)
    body = Part("ellipsoid", dict(radii=(0.55, 0.34, 0.32)), (0, 0, 0.75), textures=[fleece], density=1.2)
    head = Part("ellipsoid", dict(radii=(0.18, 0.12, 0.14)), (0.6, 0, 0.92), color=(0.15, 0.13, 0.12))
    legs = _legs((0.3, -0.3), (0.15, -0.15), 0.5, 0.05, color=(0.15, 0.13, 0.12))
    return [body, head, *legs]


def elephant() -> list[Part]:
    wrinkles = Texture("noise", scale=14.0, amount=0.1)
    body = Part("ellipsoid", dict(radii=(1.3, 0.8, 0.85)), (0, 0, 1.9), textures=[wrinkles])
    head = Part("ellipsoid", dict(radii=(0.55, 0.5, 0.55)), (1.35, 0, 2.3), textures=[wrinkles])
    trunk = Part("cone", dict(radius=0.16, height=1.5, base=False), (1.75, 0, 2.1), euler(pitch=168), textures=[wrinkles])
    ears = [Part("ellipsoid", dict(radii=(0.1, 0.5, 0.55)), (1.15, s * 0.55, 2.35), euler(yaw=s * 25), color=("primary", 0.9))
            for s in (1, -1)]
    tusks = [Part("cone", dict(radius=0.05, height=0.5, base=False), (1.7, s * 0.2, 1.9), euler(pitch=120), color=(0.95, 0.93, 0.85))
             for s in (1, -1)]
    legs = _legs((0.8, -0.8), (0.45, -0.45), 1.3, 0.26)
    return [body, head, trunk, *ears, *tusks, *legs]


def horse() -> list[Part]:
    body = Part("capsule", dict(radius=0.32, length=0.9), (0, 0, 1.25), textures=[NOISE])
    neck = Part("cylinder", dict(radius=0.17, height=0.7), (0.55, 0, 1.3), euler(pitch=35), textures=[NOISE])
    head = Part("capsule", dict(radius=0.12, length=0.35), (0.95, 0, 1.8), euler(pitch=50), textures=[NOISE])
    mane = Part("box", dict(size=(0.5, 0.06, 0.1)), (0.7, 0, 1.78), euler(pitch=-40), color=DARK)
    tail = Part("cone", dict(radius=0.08, height=0.7, base=False), (-0.8, 0, 1.35), euler(pitch=-160), color=DARK)
    legs = _legs((0.5, -0.5), (0.16, -0.16), 1.05, 0.06)
    return [body, neck, head, mane, tail, *legs]


def cow() -> list[Part]:
    patches = Texture("spots", (0.08, 0.07, 0.07), scale=7, amount=0.14)
    body = Part("box", dict(size=(1.5, 0.7, 0.75)), (0, 0, 1.05), textures=[patches, NOISE])
    head = Part("box", dict(size=(0.45, 0.35, 0.4)), (0.9, 0, 1.25), textures=[NOISE])
    horns = [Part("cone", dict(radius=0.04, height=0.2, base=False), (0.9, s * 0.16, 1.45), color=(0.9, 0.88, 0.8)) for s in (1, -1)]
    legs = _legs((0.55, -0.55), (0.22, -0.22), 0.7, 0.07)
    return [body, head, *horns, *legs]


def dog() -> list[Part]:
    body = Part("capsule", dict(radius=0.14, length=0.35), (0, 0, 0.42), textures=[NOISE])
    head = Part("ellipsoid", dict(radii=(0.14, 0.11, 0.11)), (0.33, 0, 0.6), textures=[NOISE])
    snout = Part("ellipsoid", dict(radii=(0.08, 0.06, 0.05)), (0.45, 0, 0.57), color=("primary", 0.8))
    ears = [Part("ellipsoid", dict(radii=(0.04, 0.03, 0.07)), (0.3, s * 0.09, 0.7), color=("primary", 0.6)) for s in (1, -1)]
    tail = Part("cylinder", dict(radius=0.03, height=0.22), (-0.3, 0, 0.47), euler(pitch=-50))
    legs = _legs((0.17, -0.17), (0.08, -0.08), 0.3, 0.035)
    return [body, head, snout, *ears, tail, *legs]


def cat() -> list[Part]:
    stripes = Texture("stripes", ("primary", 0.65), 14.0, axis=0, duty=0.35)
    body = Part("capsule", dict(radius=0.09, length=0.25), (0, 0, 0.24), textures=[stripes])
    head = Part("ellipsoid", dict(radii=(0.08, 0.08, 0.075)), (0.2, 0, 0.34))
    ears = [Part("cone", dict(radius=0.03, height=0.06, base=False), (0.2, s * 0.045, 0.39)) for s in (1, -1)]
    tail = Part("cylinder", dict(radius=0.018, height=0.28), (-0.2, 0, 0.27), euler(pitch=-20), textures=[stripes])
    legs = _legs((0.1, -0.1), (0.05, -0.05), 0.17, 0.022)
    return [body, head, *ears, tail, *legs]


def bird() -> list[Part]:
    body = Part("ellipsoid", dict(radii=(0.14, 0.08, 0.08)), (0, 0, 0.12), textures=[NOISE])
    head = Part("ellipsoid", dict(radii=(0.06, 0.055, 0.055)), (0.13, 0, 0.19))
    beak = Part("cone", dict(radius=0.018, height=0.06, base=False), (0.18, 0, 0.19), euler(pitch=90), color=(0.95, 0.65, 0.1))
    wings = [Part("ellipsoid", dict(radii=(0.1, 0.16, 0.015)), (-0.01, s * 0.12, 0.15), euler(roll=s * 15), color=("primary", 0.8), node="wings")
             for s in (1, -1)]
    tail = Part("box", dict(size=(0.1, 0.06, 0.01)), (-0.17, 0, 0.13), color=("primary", 0.75))
    return [body, head, beak, *wings, tail]


def duck() -> list[Part]:
    body = Part("ellipsoid", dict(radii=(0.18, 0.12, 0.1)), (0, 0, 0.1), textures=[NOISE])
    head = Part("ellipsoid", dict(radii=(0.07, 0.065, 0.07)), (0.13, 0, 0.25), color=(0.1, 0.45, 0.2))
    neck = Part("cylinder", dict(radius=0.04, height=0.1), (0.12, 0, 0.15), color=(0.1, 0.45, 0.2))
    beak = Part("ellipsoid", dict(radii=(0.05, 0.025, 0.012)), (0.21, 0, 0.24), color=(0.96, 0.7, 0.1))
    return [body, head, neck, beak]


def fish() -> list[Part]:
    stripes = Texture("stripes", (0.97, 0.96, 0.94), 7.0, axis=0, duty=0.22)
    body = Part("ellipsoid", dict(radii=(0.26, 0.07, 0.12)), (0, 0, 0.13), textures=[stripes, NOISE], node="body")
    tail = Part("ellipsoid", dict(radii=(0.07, 0.015, 0.1)), (-0.3, 0, 0.13), color=("primary", 0.85), node="tail")
    fins = [Part("ellipsoid", dict(radii=(0.06, 0.01, 0.05)), (0.0, 0, 0.25), color=("primary", 0.85)),
            Part("ellipsoid", dict(radii=(0.05, 0.05, 0.01)), (0.05, 0, 0.06), color=("primary", 0.85))]
    eyes = [Part("ellipsoid", dict(radii=(0.018, 0.01, 0.018)), (0.19, s * 0.055, 0.15), color=DARK) for s in (1, -1)]
    return [body, tail, *fins, *eyes]


# ------------------------------------------------------------------ people
def person() -> list[Part]:
    torso = Part("capsule", dict(radius=0.17, length=0.3), (0, 0, 1.2), euler(pitch=90), textures=[NOISE])
    head = Part("ellipsoid", dict(radii=(0.11, 0.1, 0.12)), (0, 0, 1.62), color=SKIN)
    hair = Part("ellipsoid", dict(radii=(0.115, 0.105, 0.08), z_min=0.0), (-0.01, 0, 1.65), color=(0.2, 0.13, 0.08))
    legs = [Part("cylinder", dict(radius=0.07, height=0.85), (0, s * 0.1, 0.0), color=(0.18, 0.22, 0.38), node=f"leg{i}")
            for i, s in enumerate((1, -1))]
    arms = [Part("cylinder", dict(radius=0.05, height=0.6), (0, s * 0.23, 0.85), color=("primary", 0.9), node=f"arm{i}")
            for i, s in enumerate((1, -1))]
    return [torso, head, hair, *legs, *arms]


def snowboarder() -> list[Part]:
    parts = person()
    parts[0] = Part("capsule", dict(radius=0.19, length=0.3), (0, 0, 1.15), euler(pitch=90), textures=[NOISE])
    board = Part("box", dict(size=(0.3, 1.5, 0.03)), (0, 0, 0.015), color=(0.1, 0.1, 0.12),
                 textures=[Texture("stripes", (0.95, 0.5, 0.1), 3.0, axis=1, duty=0.2)])
    helmet = Part("ellipsoid", dict(radii=(0.125, 0.115, 0.1), z_min=0.0), (0, 0, 1.64), color=(0.95, 0.95, 0.95))
    for i, p in enumerate(parts):
        if p.node.startswith("leg"):
            parts[i] = Part(p.shape, p.params, (p.position[0], p.position[1] * 2.5, 0.03), p.rotation, p.color, node=p.node)
    return [*parts, board, helmet]


def robot() -> list[Part]:
    body = Part("box", dict(size=(0.45, 0.5, 0.55)), (0, 0, 0.62), textures=[NOISE])
    head = Part("box", dict(size=(0.3, 0.32, 0.25)), (0, 0, 1.05), color=METAL)
    eyes = [Part("ellipsoid", dict(radii=(0.02, 0.035, 0.035)), (0.15, s * 0.08, 1.07), color=(0.2, 0.8, 1.0)) for s in (1, -1)]
    antenna = Part("cylinder", dict(radius=0.012, height=0.15), (0, 0, 1.17), color=METAL)
    arms = [Part("cylinder", dict(radius=0.05, height=0.45), (0, s * 0.31, 0.45), color=METAL) for s in (1, -1)]
    base = Part("cylinder", dict(radius=0.25, height=0.32), (0, 0, 0.02), color=(0.25, 0.25, 0.27))
    return [body, head, *eyes, antenna, *arms, base]


# ---------------------------------------------------------- tabletop things
def cube() -> list[Part]:
    return [Part("box", dict(size=(0.09, 0.09, 0.09)), (0, 0, 0.045), textures=[Texture("noise", scale=40, amount=0.04)])]


def box() -> list[Part]:
    tape = Texture("stripes", ("primary", 0.75), 1.0, axis=1, duty=0.12)
    return [Part("box", dict(size=(0.4, 0.3, 0.28)), (0, 0, 0.14), textures=[Texture("noise", scale=20, amount=0.06), tape])]


def ball() -> list[Part]:
    seam = Texture("stripes", ("primary", 0.8), 1.5, axis="u", duty=0.08)
    return [Part("ellipsoid", dict(radii=(0.13, 0.13, 0.13)), (0, 0, 0.13), textures=[seam])]


def plate() -> list[Part]:
    return [Part("cylinder", dict(radius=0.13, height=0.018, radius_top=0.14), (0, 0, 0.0),
                 textures=[Texture("rings", ("primary", 0.88), 30.0, duty=0.15)])]


def mug() -> list[Part]:
    body = Part("cylinder", dict(radius=0.045, height=0.1, caps="b"), (0, 0, 0), textures=[NOISE])
    inside = Part("disc", dict(radius=0.042), (0, 0, 0.092), color=("primary", 0.45))
    handle = Part("torus", dict(major=0.03, minor=0.009), (-0.05, 0, 0.05), euler(roll=90))
    return [body, inside, handle]


def cup() -> list[Part]:
    body = Part("cylinder", dict(radius=0.035, height=0.09, caps="b", radius_top=0.045), (0, 0, 0), textures=[NOISE])
    inside = Part("disc", dict(radius=0.043), (0, 0, 0.085), color=("primary", 0.5))
    return [body, inside]


def bowl() -> list[Part]:
    outer = Part("ellipsoid", dict(radii=(0.09, 0.09, 0.065), z_min=-1.0), (0, 0, 0.065), textures=[NOISE])
    rim = Part("torus", dict(major=0.088, minor=0.006), (0, 0, 0.065))
    inner = Part("disc", dict(radius=0.085), (0, 0, 0.055), color=("primary", 0.7))
    return [outer, inner, rim]


def bottle() -> list[Part]:
    body = Part("cylinder", dict(radius=0.035, height=0.17), (0, 0, 0), textures=[NOISE])
    neck = Part("cylinder", dict(radius=0.035, height=0.06, caps="", radius_top=0.013), (0, 0, 0.17))
    cap = Part("cylinder", dict(radius=0.014, height=0.025), (0, 0, 0.23), color=(0.95, 0.95, 0.95))
    label = Part("cylinder", dict(radius=0.0355, height=0.06, caps=""), (0, 0, 0.05), color=(0.95, 0.93, 0.86))
    return [body, neck, cap, label]


def vase() -> list[Part]:
    lower = Part("ellipsoid", dict(radii=(0.09, 0.09, 0.12)), (0, 0, 0.12), textures=[Texture("stripes", ("primary", 0.7), 20, axis=2, duty=0.2)])
    neck = Part("cylinder", dict(radius=0.04, height=0.12, caps="t", radius_top=0.06), (0, 0, 0.22))
    return [lower, neck]


def apple() -> list[Part]:
    body = Part("ellipsoid", dict(radii=(0.042, 0.042, 0.038)), (0, 0, 0.038), textures=[Texture("noise", scale=80, amount=0.07)])
    stem = Part("cylinder", dict(radius=0.003, height=0.02), (0, 0, 0.072), color=(0.35, 0.22, 0.1))
    leaf = Part("ellipsoid", dict(radii=(0.015, 0.006, 0.002)), (0.01, 0, 0.085), euler(pitch=-30), color=LEAF)
    return [body, stem, leaf]


def banana() -> list[Part]:
    segs = []
    for i, a in enumerate(np.linspace(-50, 50, 5)):
        t = np.radians(a)
        segs.append(Part("ellipsoid", dict(radii=(0.03, 0.018, 0.018)), (0.09 * np.sin(t), 0, 0.02 + 0.06 * (1 - np.cos(t))),
                         euler(pitch=-a), textures=[NOISE]))
    tips = [Part("ellipsoid", dict(radii=(0.008, 0.007, 0.007)), (s * 0.078, 0, 0.05), color=(0.25, 0.18, 0.08)) for s in (1, -1)]
    return segs + tips


def book() -> list[Part]:
    cover = Part("box", dict(size=(0.22, 0.16, 0.035)), (0, 0, 0.0175), textures=[NOISE])
    pages = Part("box", dict(size=(0.21, 0.002, 0.03), faces="y"), (0, -0.079, 0.0175), color=(0.95, 0.93, 0.86))
    return [cover, pages]


def lamp() -> list[Part]:
    base = Part("cylinder", dict(radius=0.12, height=0.03), (0, 0, 0), color=(0.2, 0.2, 0.22))
    pole = Part("cylinder", dict(radius=0.012, height=0.4, caps=""), (0, 0, 0.03), color=METAL)
    shade = Part("cylinder", dict(radius=0.15, height=0.18, caps="", radius_top=0.08), (0, 0, 0.38), textures=[NOISE])
    bulb = Part("ellipsoid", dict(radii=(0.04, 0.04, 0.05)), (0, 0, 0.42), color=(1.0, 0.97, 0.8))
    return [base, pole, shade, bulb]


# -------------------------------------------------------------- furniture
def table() -> list[Part]:
    grain = Texture("stripes", ("primary", 0.82), 9.0, axis=0, duty=0.3)
    top = Part("box", dict(size=(1.4, 0.9, 0.05)), (0, 0, 0.725), textures=[grain, NOISE])
    legs = [Part("box", dict(size=(0.06, 0.06, 0.7)), (x, y, 0.35), color=("primary", 0.8)) for x in (0.62, -0.62) for y in (0.38, -0.38)]
    return [top, *legs]


def chair() -> list[Part]:
    seat = Part("box", dict(size=(0.45, 0.45, 0.05)), (0, 0, 0.45), textures=[NOISE])
    back = Part("box", dict(size=(0.05, 0.45, 0.5)), (-0.2, 0, 0.72), textures=[NOISE])
    legs = [Part("box", dict(size=(0.04, 0.04, 0.45)), (x, y, 0.225), color=("primary", 0.8)) for x in (0.19, -0.19) for y in (0.19, -0.19)]
    return [seat, back, *legs]


def house() -> list[Part]:
    walls = Part("box", dict(size=(4.0, 3.5, 2.8)), (0, 0, 1.4), textures=[Texture("noise", scale=3, amount=0.05)])
    roof = [Part("box", dict(size=(4.4, 2.2, 0.12)), (0, s * 0.95, 3.35), euler(roll=s * 35), color=(0.55, 0.15, 0.1),
                 textures=[Texture("stripes", (0.42, 0.1, 0.08), 6.0, axis=1, duty=0.2)]) for s in (1, -1)]
    gable = [Part("cone", dict(radius=1.75, height=1.15, base=False), (s * 2.0, 0, 2.8), euler(pitch=0), color="primary") for s in (1, -1)]
    door = Part("box", dict(size=(0.02, 0.9, 1.8), faces="y"), (0, -1.76, 0.9), euler(yaw=90), color=(0.35, 0.2, 0.1))
    windows = [Part("box", dict(size=(0.8, 0.02, 0.8), faces="y"), (x, -1.76, 1.7), color=(0.5, 0.65, 0.8)) for x in (-1.2, 1.2)]
    return [walls, *roof, *gable, door, *windows]


# ------------------------------------------------------------------ nature
def tree() -> list[Part]:
    trunk = Part("cylinder", dict(radius=0.18, height=1.8, radius_top=0.12), (0, 0, 0), color=(0.4, 0.26, 0.14),
                 textures=[Texture("stripes", (0.3, 0.19, 0.1), 12.0, axis="u", duty=0.3)])
    leaves = Texture("noise", scale=10.0, amount=0.2)
    crowns = [Part("ellipsoid", dict(radii=(0.95, 0.95, 1.05)), (0, 0, 2.55), textures=[leaves], density=1.2),
              Part("ellipsoid", dict(radii=(0.6, 0.6, 0.6)), (0.4, 0.3, 3.2), textures=[leaves]),
              Part("ellipsoid", dict(radii=(0.6, 0.6, 0.6)), (-0.4, -0.3, 3.1), textures=[leaves])]
    return [trunk, *crowns]


def seaweed() -> list[Part]:
    fronds = []
    for i, (x, y, h, lean) in enumerate([(0, 0, 1.0, 6), (0.12, 0.08, 0.8, -8), (-0.1, -0.06, 0.9, 10), (0.05, -0.12, 0.7, -4)]):
        for k in range(4):
            z0 = k * h / 4
            fronds.append(Part("ellipsoid", dict(radii=(0.05, 0.015, h / 7)), (x + np.sin(np.radians(lean)) * z0, y, z0 + h / 8),
                               euler(pitch=lean * (1 + k * 0.4)), textures=[Texture("noise", scale=20, amount=0.12)],
                               node=f"frond{k}"))
    return fronds


def rock() -> list[Part]:
    return [Part("ellipsoid", dict(radii=(0.35, 0.28, 0.22)), (0, 0, 0.18), textures=[Texture("noise", scale=18, amount=0.2)]),
            Part("ellipsoid", dict(radii=(0.2, 0.18, 0.15)), (0.2, 0.12, 0.12), textures=[Texture("noise", scale=18, amount=0.2)])]


def traffic_cone() -> list[Part]:
    band = Texture("stripes", (0.97, 0.97, 0.97), 1 / 0.5, axis=2, duty=0.0)
    body = Part("cone", dict(radius=0.15, height=0.5, base=False), (0, 0, 0.03),
                textures=[Texture("stripes", (0.97, 0.97, 0.97), 6.0, axis=2, duty=0.3), band])
    base = Part("box", dict(size=(0.36, 0.36, 0.03)), (0, 0, 0.015), color=("primary", 0.8))
    return [body, base]


CATEGORY_SPECS: dict[str, CategorySpec] = {s.name: s for s in [
    CategorySpec("fish", fish, (0.98, 0.5, 0.1), "swim", "water", 2000),
    CategorySpec("seaweed", seaweed, (0.16, 0.55, 0.22), "fixed", "water", 2000),
    CategorySpec("bus", bus, (0.85, 0.15, 0.12), "ground", "road", 3200),
    CategorySpec("boat", boat, (0.92, 0.92, 0.95), "float", "water", 2600),
    CategorySpec("car", car, (0.15, 0.35, 0.8), "ground", "road", 2800),
    CategorySpec("ball", ball, (0.9, 0.15, 0.12), "ground", "ground", 1600, rolls=True),
    CategorySpec("motorcycle", motorcycle, (0.08, 0.08, 0.09), "ground", "road", 2400),
    CategorySpec("sheep", sheep, (0.93, 0.92, 0.88), "ground", "grass", 2400),
    CategorySpec("elephant", elephant, (0.55, 0.53, 0.52), "ground", "grass", 3200),
    CategorySpec("snowboarder", snowboarder, (0.9, 0.3, 0.1), "ground", "snow", 2400),
    CategorySpec("cube", cube, (0.85, 0.12, 0.12), "ground", "table", 1200),
    CategorySpec("plate", plate, (0.95, 0.95, 0.93), "fixed", "table", 1400),
    CategorySpec("table", table, (0.6, 0.4, 0.22), "fixed", "indoor", 2600),
    CategorySpec("mug", mug, (0.2, 0.45, 0.8), "ground", "table", 1400),
    CategorySpec("bottle", bottle, (0.2, 0.6, 0.3), "ground", "table", 1400),
    CategorySpec("box", box, (0.72, 0.55, 0.35), "ground", "ground", 1600),
    CategorySpec("robot", robot, (0.9, 0.9, 0.92), "ground", "indoor", 2600),
    CategorySpec("person", person, (0.2, 0.4, 0.75), "ground", "ground", 2600),
    CategorySpec("dog", dog, (0.7, 0.5, 0.28), "ground", "grass", 2200),
    CategorySpec("cat", cat, (0.85, 0.55, 0.25), "ground", "indoor", 2000),
    CategorySpec("tree", tree, (0.2, 0.52, 0.18), "fixed", "grass", 3000),
    CategorySpec("chair", chair, (0.55, 0.35, 0.2), "ground", "indoor", 2000),
    CategorySpec("bicycle", bicycle, (0.1, 0.45, 0.75), "ground", "road", 2000),
    CategorySpec("bird", bird, (0.25, 0.45, 0.85), "air", "sky", 1600),
    CategorySpec("horse", horse, (0.45, 0.28, 0.15), "ground", "grass", 2600),
    CategorySpec("cow", cow, (0.95, 0.94, 0.92), "ground", "grass", 2600),
    CategorySpec("truck", truck, (0.9, 0.75, 0.2), "ground", "road", 3000),
    CategorySpec("duck", duck, (0.55, 0.42, 0.3), "float", "water", 1600),
    CategorySpec("cup", cup, (0.95, 0.95, 0.92), "ground", "table", 1200),
    CategorySpec("bowl", bowl, (0.85, 0.3, 0.2), "ground", "table", 1400),
    CategorySpec("apple", apple, (0.8, 0.1, 0.1), "ground", "table", 1000),
    CategorySpec("banana", banana, (0.97, 0.85, 0.2), "ground", "table", 1200),
    CategorySpec("lamp", lamp, (0.95, 0.9, 0.75), "fixed", "indoor", 1600),
    CategorySpec("vase", vase, (0.3, 0.5, 0.75), "ground", "table", 1400),
    CategorySpec("book", book, (0.6, 0.15, 0.15), "ground", "table", 1000),
    CategorySpec("cone", traffic_cone, (0.98, 0.45, 0.08), "ground", "road", 1200),
    CategorySpec("rock", rock, (0.5, 0.48, 0.45), "fixed", "ground", 1600),
    CategorySpec("house", house, (0.9, 0.86, 0.75), "fixed", "grass", 3000),
    CategorySpec("airplane", airplane, (0.92, 0.93, 0.95), "air", "sky", 2800),
    CategorySpec("train", train, (0.2, 0.35, 0.6), "ground", "ground", 3200),
]}


# ------------------------------------------------------------ basic shapes (always available)
_SHAPE_TEXTURE = Texture("noise", scale=12.0, amount=0.05)


def _shape(shape: str, params: dict, z: float, rotation=None) -> Callable[[], list[Part]]:
    def build() -> list[Part]:
        return [Part(shape, params, (0, 0, z), euler() if rotation is None else rotation, textures=[_SHAPE_TEXTURE])]
    return build


# shape name -> spec; grounded by name (open vocabulary), never by the rule vocabulary
SHAPE_SPECS: dict[str, CategorySpec] = {s.name: s for s in [
    CategorySpec("cylinder", _shape("cylinder", dict(radius=0.12, height=0.3), 0.0), (0.2, 0.45, 0.8), "ground", "table", 1400),
    CategorySpec("sphere", _shape("ellipsoid", dict(radii=(0.15, 0.15, 0.15)), 0.15), (0.85, 0.2, 0.15), "ground", "ground", 1400,
                 rolls=True),
    CategorySpec("torus", _shape("torus", dict(major=0.15, minor=0.05), 0.05), (0.9, 0.7, 0.2), "ground", "table", 1400),
    CategorySpec("capsule", _shape("capsule", dict(radius=0.08, length=0.25), 0.08), (0.3, 0.7, 0.4), "ground", "table", 1400),
    CategorySpec("pyramid", _shape("pyramid", dict(base=0.3, height=0.25), 0.0), (0.85, 0.75, 0.45), "ground", "ground", 1400),
    CategorySpec("disc", _shape("cylinder", dict(radius=0.15, height=0.02), 0.0), (0.7, 0.7, 0.75), "ground", "table", 1200),
    CategorySpec("plank", _shape("box", dict(size=(0.8, 0.15, 0.03)), 0.015), (0.6, 0.42, 0.25), "ground", "ground", 1400),
]}


def category_names() -> list[str]:
    """All categories the library can build."""
    return sorted(CATEGORY_SPECS)


def build_parts(category: str) -> list[Part]:
    """The parts of one object of this category (nominal size, object frame)."""
    spec = CATEGORY_SPECS.get(category) or SHAPE_SPECS.get(category)
    if spec is None:
        raise ValueError(f"Expected a category of the library, found {category!r}; known: {category_names()} "
                         f"and the shapes {sorted(SHAPE_SPECS)}")
    return spec.build()
