"""Compose a generate `Plan` into a ground-truth `Scene4D`: setting, objects, camera, motion.

Layout rules (documented so that users can predict a scene from its prompt):

* the generation camera looks along world +y (image right = +x, image up = +z), pitched
  down over ground-like settings, level under water and in the sky; its distance frames
  the largest moving object at about a fifth of the image width, and every object;
* moving objects are centred on the view (several movers take rows at different depths);
  a landmark a mover goes to sits on the right if the mover starts on the left, and so
  on; objects that only stand by line up behind the movers;
* every object is one rigid node of the motion scaffold (static ones keep an identity
  pose), so edits can later move anything; the setting is static;
* canonical Gaussians are the scene at t = 0; node poses map them to each frame.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any, Sequence

import numpy as np

from ..limits import check_clip_size
from ..language.sequence import motion_stages
from ..language.substitutions import plan_substitutions
from ..scene import Camera, Gaussians, Motion, Provenance, Scene4D, SceneObject
from ..scene.camera import camera_path
from ..scene.parts import TANGENTIAL_SCALE, SurfaceCloud, parts_to_gaussians
from ..scene.sky import check_sky
from ..scene.rotations import axis_angle_to_quat, matrix_to_quat, quat_multiply, quat_to_matrix
from .assets import CATEGORY_SPECS, SHAPE_SPECS, CategorySpec, build_parts
from . import open_assets  # noqa: F401  (registers real assets as open-vocabulary candidates)
from .real_assets import ASSET_MODES, ASSET_PREFIX, asset_cloud, pick_asset, setting_sky, uses_assets
from .color_match import match_mean_color, tint_keep_shading
from .settings import Setting, build_setting, carve_under, setting_levels
from .trajectory import MotionRequest, PlannedTrajectory, bounce_height, plan_trajectory
from .stages import fall, fall_drop, is_fall, second_stage

__all__ = ["GenerationConfig", "ComposedScene", "compose_scene"]

MAX_INSTANCES = 12
MIN_RELATIVE_SIZE = 0.3   # no object is smaller than this fraction of the scene's largest one
RECEPTACLES = ("plate", "bowl", "table")
VIEW_PITCH = math.radians(20.0)            # the generation camera looks down this much over the ground   # things go onto these; other landmarks are approached


@dataclass(frozen=True)
class GenerationConfig:
    """Clip and scene settings of the procedural generator.

    Attributes:
        num_frames: frames of the clip (49, as CogVideoX).
        fps: frames per second (8, as CogVideoX).
        width, height: frame size in pixels.
        fov_y_deg: vertical field of view of the generation camera.
        detail: multiplier on every Gaussian budget (1.0: ~2-3k per object, ~9k for the setting).
        setting_budget: Gaussians of the setting at detail 1.
        frame_fraction: width of the largest moving object as a fraction of the image width.
        assets: "auto" (real assets where installed, see `real_assets`), "off" (procedural only,
            bit-identical to the generator without assets) or "require".
    """

    num_frames: int = 49
    fps: float = 8.0
    width: int = 128
    height: int = 128
    fov_y_deg: float = 50.0
    detail: float = 1.0
    setting_budget: int = 9000
    frame_fraction: float = 0.3
    assets: str = "auto"

    def __post_init__(self) -> None:
        if not (isinstance(self.num_frames, int) and 1 <= self.num_frames <= 1000):
            raise ValueError(f"Expected num_frames in [1, 1000], found {self.num_frames!r}")
        if not (self.fps > 0 and math.isfinite(self.fps)):
            raise ValueError(f"Expected fps > 0, found {self.fps!r}")
        for k in ("width", "height"):
            v = getattr(self, k)
            if not (isinstance(v, int) and 16 <= v <= 4096):
                raise ValueError(f"Expected {k} in [16, 4096], found {v!r}")
        check_clip_size(self.num_frames, self.width, self.height)
        if not 0 < self.detail <= 16:
            raise ValueError(f"Expected detail in (0, 16], found {self.detail!r}")
        if not 0 < self.frame_fraction < 1:
            raise ValueError(f"Expected frame_fraction in (0, 1), found {self.frame_fraction!r}")
        if self.assets not in ASSET_MODES:
            raise ValueError(f"Expected assets in {ASSET_MODES}, found {self.assets!r}")


@dataclass
class Instance:
    """One object instance being composed."""

    spec: Any                      # the plan's ObjectSpec
    name: str
    category: str
    color: np.ndarray
    asked_color: tuple | None
    scale: float
    cloud: SurfaceCloud | None = None
    half: np.ndarray = field(default_factory=lambda: np.zeros(3))
    base_offset: float = 0.0       # world z of the object frame's origin above the anchor
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    trajectory: PlannedTrajectory | None = None
    mobility: str = "ground"
    asset: str | None = None       # "source/id" of the real asset used, None when procedural


@dataclass
class ComposedScene:
    """What composition produced: the scene and the plan's trajectories (by object name)."""

    scene: Scene4D
    trajectories: dict[str, PlannedTrajectory]
    setting: Setting
    cameras: list[Camera]


OPEN_SPEC = CategorySpec("asset", lambda: [], (0.7, 0.7, 0.7), "ground", "ground", 2400)


def category_spec(category: str) -> CategorySpec | None:
    """The spec of a library category, a basic shape, or an open "asset:<id>" category (None: unknown)."""
    if category.startswith(ASSET_PREFIX):
        return OPEN_SPEC
    return CATEGORY_SPECS.get(category) or SHAPE_SPECS.get(category)


def _instances(plan: Any, config: GenerationConfig) -> list[Instance]:
    out = []
    total = sum(o.count for o in plan.objects)
    if total > MAX_INSTANCES:
        raise ValueError(f"Expected at most {MAX_INSTANCES} object instances in one scene, found {total}")
    for spec in plan.objects:
        cat = category_spec(spec.category)
        if cat is None:
            raise ValueError(f"Expected a category of the generator's library, found {spec.category!r}; "
                             f"known: {sorted(CATEGORY_SPECS)}")
        rgb = np.asarray(spec.color.rgb if spec.color is not None else cat.color, dtype=np.float64)
        for k in range(spec.count):
            name = spec.name if spec.count == 1 else f"{spec.name} {k + 1}"
            out.append(Instance(spec, name, spec.category, rgb, None if spec.color is None else tuple(spec.color.rgb),
                                float(spec.scale), mobility=cat.mobility))
    return out


def _choose_setting(plan: Any, instances: Sequence[Instance]) -> str:
    setting = plan.setting or "ground"
    if setting == "water" and any(i.mobility == "swim" or i.category == "seaweed" for i in instances):
        return "underwater"
    return setting


def _rescale(inst: Instance, factor: float) -> None:
    """Grow an instance (its cloud is centred in x, y and rests on z = 0)."""
    inst.scale *= factor
    inst.cloud.means = inst.cloud.means * factor
    inst.cloud.scales = inst.cloud.scales * factor
    inst.half = inst.half * factor


@functools.lru_cache(maxsize=64)
def _procedural_longest(category: str) -> float:
    """Longest side (m) of the procedural builder's object: real assets take this size."""
    c = parts_to_gaussians(build_parts(category), 400, np.full(3, 0.5), np.random.default_rng(0))
    return float(np.max(c.means.max(0) - c.means.min(0)))


def _base_cloud(inst: Instance, budget: int, rng: np.random.Generator, seed: int, k: int,
                real: bool, moving: bool = False) -> SurfaceCloud:
    """The object's cloud: a real asset where one matches (and `real`), else the procedural builder.
    A moving asset faces +x like the builders (it travels nose first); a still one faces the camera."""
    open_cat = inst.category.startswith(ASSET_PREFIX)
    record = pick_asset(inst.category, seed, k) if (real or open_cat) else None
    if record is None:
        if open_cat:
            raise ValueError(f"Expected an installed asset for {inst.category!r}, found none")
        return parts_to_gaussians(build_parts(inst.category), budget, inst.color, rng)
    inst.asset = f"{record.source}/{record.id}" if not record.id.startswith(record.source + "/") else record.id
    return asset_cloud(record, budget, None if open_cat else _procedural_longest(inst.category), seed=0,
                       front_to_x=moving)


def _object_cloud(inst: Instance, rng: np.random.Generator, config: GenerationConfig, seed: int = 0, k: int = 0,
                  real: bool = False, moving: bool = False) -> None:
    cat = category_spec(inst.category)
    budget = max(200, int(cat.budget * config.detail))
    cloud = _base_cloud(inst, budget, rng, seed, k, real, moving)
    if inst.asked_color is not None:
        # the object as a whole reads as the asked colour: the mean of what a camera sees from the
        # side and slightly above (projected area of each surface Gaussian) matches in Lab
        normals = quat_to_matrix(cloud.quats)[:, :, 2]
        seen = np.abs(normals[:, 1]) * math.cos(VIEW_PITCH) + np.clip(normals[:, 2], 0, None) * math.sin(VIEW_PITCH)
        area = cloud.scales[:, 0] * cloud.scales[:, 1] * cloud.opacities * (0.05 + seen)
        recolour = tint_keep_shading if inst.asset is not None else match_mean_color
        cloud.colors = recolour(cloud.colors, area, inst.asked_color)
    cloud.means = cloud.means * inst.scale
    cloud.scales = cloud.scales * inst.scale
    lo, hi = cloud.means.min(0), cloud.means.max(0)
    # centre in x, y; base on z = 0
    shift = np.array([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    cloud.means = cloud.means + shift
    inst.half = (hi - lo) / 2
    inst.cloud = cloud


def compose_scene(plan: Any, seed: int, config: GenerationConfig | None = None, prompt: str | None = None) -> ComposedScene:
    """Build the ground-truth scene and trajectories of a generate plan.

    Args:
        plan: a generate-mode `morphosim_gym.language.Plan`.
        seed: the random seed (same plan and seed: bit-identical scene).
        config: clip settings.
        prompt: the text, recorded in the scene's provenance.
    """
    config = config or GenerationConfig()
    if getattr(plan, "mode", None) != "generate":
        raise ValueError(f"Expected a generate plan, found mode {getattr(plan, 'mode', None)!r}")
    instances = _instances(plan, config)
    setting_name = _choose_setting(plan, instances)
    if setting_name == "underwater" and not any(i.category == "seaweed" for i in instances):
        # the sea floor comes with seaweed (as the paper's fish scene has), an object edits can name
        dressing = SimpleNamespace(name="seaweed", noun="seaweed", category="seaweed", color=None, scale=1.0, count=1)
        spec = CATEGORY_SPECS["seaweed"]
        instances.append(Instance(dressing, "seaweed", "seaweed", np.asarray(spec.color), None, 1.0,
                                  mobility=spec.mobility))
    real = uses_assets(config.assets)
    motions = {m.target: m for m in plan.motions}
    for k, inst in enumerate(instances):
        m = motions.get(inst.spec.name)
        _object_cloud(inst, np.random.default_rng([seed, 1, k]), config, seed, k, real,
                      moving=m is not None and m.path != "stop")
    by_spec: dict[str, list[Instance]] = {}
    for inst in instances:
        by_spec.setdefault(inst.spec.name, []).append(inst)

    def moves(inst: Instance) -> bool:
        m = motions.get(inst.spec.name)
        return m is not None and m.path != "stop"

    movers = [i for i in instances if moves(i)]
    standers = [i for i in instances if not moves(i)]
    # ---- visibility floor: a named object is never tiny next to the largest one
    largest = max(float(max(i.half[0], i.half[1], i.half[2])) for i in instances)
    for inst in instances:
        own = float(max(inst.half[0], inst.half[1], inst.half[2]))
        if own < MIN_RELATIVE_SIZE * largest:
            _rescale(inst, MIN_RELATIVE_SIZE * largest / own)
    # ---- scale of the scene and the camera framing
    key = movers or instances
    size = max((float(max(i.half[0], i.half[1])) * 2 for i in key), default=1.0)
    size = max(size, 0.05)
    fx_over_w = 0.5 / math.tan(math.radians(config.fov_y_deg) / 2) * config.height / config.width
    distance = size / config.frame_fraction * fx_over_w
    all_size = max((float(max(i.half[0], i.half[1])) * 2 for i in instances), default=size)
    distance = max(distance, all_size * 1.6 * fx_over_w / 0.8)
    landmark_names = {getattr(m, k) for m in plan.motions for k in ("end", "start", "around") if getattr(m, k)}
    meeting = _meeting_pairs(plan)
    back = [i for i in standers if i.spec.name not in landmark_names]
    spacing = all_size * 1.3
    row_half = (len(back) - 1) / 2 * spacing + all_size / 2
    # the row of standing objects fits in 80% of the view's width
    distance = max(distance, row_half / 0.4 * fx_over_w)
    pitch = math.radians(4.0) if setting_name in ("underwater", "sky") else VIEW_PITCH
    levels = setting_levels(setting_name)
    heights = {}
    for inst in instances:
        if inst.mobility == "air":
            heights[inst.name] = max(levels["air_height"], distance * 0.35) if setting_name != "sky" else 0.0
        elif inst.mobility == "swim" and levels["swim_height"] is not None:
            heights[inst.name] = levels["swim_height"] * max(1.0, size / 0.5) * 0.6 + inst.half[2]
        elif inst.mobility == "float" and levels["water_level"] is not None:
            heights[inst.name] = levels["water_level"] - 0.12 * inst.half[2] * 2   # a shallow draft
        else:
            heights[inst.name] = 0.0
    lift = {i.name: _lift_of(motions.get(i.spec.name), i) for i in instances}
    focus_z = float(np.mean([heights[i.name] + i.half[2] + lift[i.name] / 2 for i in key])) if key else 0.5
    tall = max((2 * float(i.half[2]) + lift[i.name] for i in key), default=size)
    fy_over_h = 0.5 / math.tan(math.radians(config.fov_y_deg) / 2)
    distance = max(distance, tall / 0.55 * fy_over_h)
    for _ in range(6):
        eye = np.array([0.0, -distance * math.cos(pitch), focus_z + distance * math.sin(pitch)])
        base_cam = Camera.look_at(eye, (0.0, 0.0, focus_z), config.width, config.height, config.fov_y_deg)
        span = distance * config.width / (2 * base_cam.fx)    # half-width of the view at the centre, metres
        _place(plan, movers, back, standers, landmark_names, by_spec, heights, size, span, spacing)
        _place_meeting(meeting, by_spec, span)
        reach = max(abs(float(i.position[0])) + float(max(i.half[:2])) for i in instances)
        if reach <= 0.85 * span:
            break
        distance *= reach / (0.85 * span)

    # ---- receptacles: things that go "to" a plate / bowl / table end on top of it
    top_of = {}
    for inst in standers:
        if inst.category in RECEPTACLES:
            top_of[inst.spec.name] = float(inst.position[2] + 2 * inst.half[2] * (0.35 if inst.category == "bowl" else 1.0))

    # ---- camera path, then the setting detailed where it looks
    cameras = camera_path(plan.camera, base_cam, np.array([0.0, 0.0, focus_z]), config.num_frames)
    setting = build_setting(setting_name, radius=max(distance * 3.5, 6.0 * size), rng=np.random.default_rng([seed, 2]),
                            budget=int(config.setting_budget * config.detail), cameras=cameras)
    # ---- motion planning
    trajectories: dict[str, PlannedTrajectory] = {}
    stages = motion_stages(plan)
    for inst in movers:
        m = motions[inst.spec.name]
        req = _meeting_request(m, inst, by_spec) if inst.spec.name in meeting else _request(m, inst, by_spec, top_of)
        vertical = inst.mobility in ("air", "swim")
        traj = plan_trajectory(req, cameras, config.num_frames, config.fps, inst.half, inst.position,
                               vertical_plane=vertical, rolls=category_spec(inst.category).rolls)
        if req.path == "to" and req.end_height is not None:
            traj.positions[:, 2] = _rise_onto(traj.positions, req.end_height, inst.position[2])
        traj = _staged(traj, m, inst, stages.get(inst.spec.name), cameras, vertical)
        inst.trajectory = traj
        trajectories[inst.name] = traj
    # ---- assemble Gaussians, objects and the motion scaffold
    scene = _assemble(plan, instances, setting, cameras, config, seed, prompt)
    sky = setting_sky(setting_name, seed) if real else None
    if sky is not None:
        scene.sky = check_sky(sky)    # set before anything reads (or hashes) the scene
    return ComposedScene(scene, trajectories, setting, cameras)


def _place(plan: Any, movers: list, back: list, standers: list, landmark_names: set, by_spec: dict, heights: dict,
           size: float, span: float, spacing: float) -> None:
    """Positions of every instance for a view `span` metres half-wide at the centre.

    Movers take rows at different depths (bigger ones further back, smaller in front,
    staggered sideways; swimmers and flyers also spread in height); objects that only stand by
    line up behind them; landmarks sit where their mover goes around, starts or ends: on
    either side of it along its direction (or left to right), far enough apart for their sizes.
    """
    by_size = sorted(movers, key=lambda i: -float(max(i.half)))
    for r, inst in enumerate(by_size):
        row = [0.0, -1.0, 1.0, -0.5, 0.5, -1.5, 1.5][r % 7] * max(size, 0.2 * span) * 0.9
        lateral = 0.0 if r == 0 else (1.0 if r % 2 else -1.0) * (0.15 + 0.1 * (r // 3)) * span
        z = heights[inst.name]
        if inst.mobility in ("air", "swim") and r:
            z += (1.0 if r % 2 else -1.0) * 0.6 * size * (1 + r // 3)
            z = max(z, float(inst.half[2]) * 1.2)
        inst.position = np.array([lateral, row, z])
    for k, inst in enumerate(back):
        x = (k - (len(back) - 1) / 2) * spacing
        y = (1.2 if movers else 0.0) * max(size, 0.2 * span)
        inst.position = np.array([x, y, heights[inst.name]])
    for inst in standers:
        if inst.spec.name not in landmark_names:
            continue
        m = next(m for m in plan.motions if inst.spec.name in (m.end, m.start, m.around))
        mover = by_spec[m.target][0]
        if m.around == inst.spec.name:
            inst.position = np.array([mover.position[0], mover.position[1], heights[inst.name]])
            continue
        d = m.direction_world
        side = 1.0 if d is None or d[0] >= 0 else -1.0
        if m.start == inst.spec.name:
            side = -side
        offset = max(0.4 * span, float(max(inst.half[:2])) + 3.0 * float(max(mover.half[:2])))
        inst.position = np.array([mover.position[0] + side * offset, mover.position[1], heights[inst.name]])


def _meeting_pairs(plan: Any) -> dict[str, str]:
    """Movers that head for each other ("two cars drive towards each other"): name -> the other's name."""
    ends = {m.target: m.end for m in plan.motions if m.end is not None and m.path != "stop"}
    return {a: b for a, b in ends.items() if ends.get(b) == a}


def _place_meeting(meeting: dict[str, str], by_spec: dict, span: float) -> None:
    """Two objects that meet start in one lane (the first one's), on either side of the centre."""
    for a, b in meeting.items():
        if a > b:
            continue
        first, second = by_spec[a][0], by_spec[b][0]
        offset = 0.6 * span
        lane = float(first.position[1])
        left, right = (first, second) if a == min(meeting) else (second, first)
        left.position = np.array([-offset, lane, float(left.position[2])])
        right.position = np.array([offset, lane, float(right.position[2])])


def _meeting_request(m: Any, inst: Instance, by_spec: dict) -> MotionRequest:
    """Drive from where it stands to the midpoint between it and the other, stopping its own half-length
    short of it: the two meet nose to nose without overlapping."""
    other = by_spec[m.end][0]
    mid = (np.asarray(inst.position) + np.asarray(other.position)) / 2
    return MotionRequest("to", tuple(m.direction_world), m.speed, start=tuple(inst.position), end=tuple(mid),
                         clearance=1.05 * float(inst.half[0]))          # half[0]: along its heading


def _rise_onto(positions: np.ndarray, top: float, rest: float) -> np.ndarray:
    """Anchor heights climbing onto a receptacle over the last part of the approach."""
    end = positions[-1, :2]
    d = np.linalg.norm(positions[:, :2] - end, axis=1)
    ramp = np.clip(1.0 - d / max(float(d.max()) * 0.25, 1e-6), 0.0, 1.0)
    return rest + (top - rest) * ramp


def _request(m: Any, inst: Instance, by_spec: dict, top_of: dict) -> MotionRequest:
    def pos(name: str | None):
        return None if name is None else tuple(by_spec[name][0].position)

    direction = tuple(m.direction_world) if m.direction_world is not None else (1.0, 0.0, 0.0)
    path = m.path
    if m.end is not None and path in ("straight", "bounce", "zigzag", "oscillate"):
        def gap(other: str | None) -> float:
            if other is None or other in top_of:
                return 0.0
            return 1.1 * (float(max(inst.half[:2])) + float(max(by_spec[other][0].half[:2])))

        return MotionRequest("to", direction, m.speed, start=pos(m.start), end=pos(m.end),
                             end_height=top_of.get(m.end), clearance=gap(m.end), start_clearance=gap(m.start))
    if path == "circle":
        return MotionRequest("circle", direction, m.speed, clockwise=m.clockwise is not False,
                             center=pos(m.around) if m.around else None)
    return MotionRequest(path, direction, m.speed, start=pos(m.start))


def _lift_of(m: Any, inst: Instance) -> float:
    """How far above its rest height an object's motion takes it (a bounce, a fall's start): framed by the camera."""
    if m is None:
        return 0.0
    if m.path == "bounce":
        return bounce_height(inst.half)
    return fall_drop(inst.half) if is_fall(m.direction_world, m.path, inst.mobility) else 0.0


def _staged(traj: PlannedTrajectory, m: Any, inst: Instance, stage: Any, cameras: list[Camera],
            vertical: bool) -> PlannedTrajectory:
    """A planned trajectory as a fall under gravity when it is one, then with its second stage if any."""
    if is_fall(m.direction_world, m.path, inst.mobility):
        traj = fall(traj, float(inst.position[2]), fall_drop(inst.half), cameras, inst.half)
    if stage is not None:
        d = m.direction_world
        upright = vertical or (d is not None and abs(float(d[2])) > 0.7 and not is_fall(d, m.path, inst.mobility))
        traj = second_stage(traj, stage, cameras, inst.half, anchor_is_base=not upright)
    return traj


def _yaw_quat(yaw: np.ndarray) -> np.ndarray:
    return axis_angle_to_quat(np.array([0.0, 0.0, 1.0]), yaw)


def _assemble(plan: Any, instances: list[Instance], setting: Setting, cameras: list[Camera],
              config: GenerationConfig, seed: int, prompt: str | None) -> Scene4D:
    T = config.num_frames
    objects = [SceneObject(0, setting.label, setting.name if setting.name != "underwater" else "water",
                           role="background")]
    parts = {k: [] for k in ("means", "quats", "scales", "opacities", "colors", "ids", "nodes")}

    def add(cloud: SurfaceCloud, means: np.ndarray, quats: np.ndarray, obj_id: int, node: int) -> None:
        parts["means"].append(means)
        parts["quats"].append(quats)
        parts["scales"].append(cloud.scales)
        parts["opacities"].append(cloud.opacities)
        parts["colors"].append(cloud.colors)
        parts["ids"].append(np.full(len(means), obj_id))
        parts["nodes"].append(np.full(len(means), node))

    rotations = np.zeros((T, len(instances), 4))
    translations = np.zeros((T, len(instances), 3))
    placed = []
    for k, inst in enumerate(instances):
        obj_id = k + 1
        objects.append(SceneObject(obj_id, inst.name, inst.category, color=inst.asked_color,
                                   dynamic=inst.trajectory is not None, asset=inst.asset))
        traj = inst.trajectory
        if traj is not None:
            pos, yaw, spin = traj.positions, traj.headings, traj.spins
        else:
            pos = np.tile(inst.position, (T, 1))
            right = cameras[0].camera_to_world[:3, 0]
            yaw = np.full(T, math.atan2(right[1], right[0]) + (math.pi / 2 if inst.category in ("chair", "house") else 0.0))
            spin = np.zeros(T)
        q = _yaw_quat(yaw)
        if np.any(spin):
            roll = axis_angle_to_quat(np.array([0.0, 1.0, 0.0]), spin)     # rolling forward about local y
            q = quat_multiply(q, roll)
        centre = np.array([0.0, 0.0, inst.half[2]])                          # roll about the object's centre
        mats = quat_to_matrix(q)
        # world position of the object frame's origin: anchor minus (rotated centre offset) plus centre lift
        if inst.mobility in ("air", "swim") and traj is not None:
            origin = pos - np.array([0.0, 0.0, inst.half[2]])
        else:
            origin = pos
        world_origin = origin + np.array([0.0, 0.0, inst.half[2]]) - np.einsum("tij,j->ti", mats, centre)
        # canonical = frame 0 pose; node pose at t maps frame-0 world to frame-t world
        r0 = mats[0]
        c = inst.cloud
        means0 = c.means @ r0.T + world_origin[0]
        quats0 = quat_multiply(np.broadcast_to(q[0], (len(c), 4)), c.quats)
        rel_mats = np.einsum("tij,kj->tik", mats, r0)                       # R_t R_0^T
        rel_q = matrix_to_quat(rel_mats)
        rotations[:, k] = rel_q
        translations[:, k] = world_origin - np.einsum("tij,j->ti", rel_mats, world_origin[0])
        placed.append((c, means0, quats0, obj_id, k, traj is None))
    # the setting, less what a resting object's base hides for the whole clip
    s = setting.cloud
    for c, means0, _, _, _, static in placed:
        if static and len(c):
            spacing = float(np.median(c.scales[:, :2])) / TANGENTIAL_SCALE
            s = carve_under(s, means0[means0[:, 2] <= means0[:, 2].min() + spacing], spacing)
    add(s, s.means, s.quats, 0, -1)
    for c, means0, quats0, obj_id, k, _ in placed:
        add(c, means0, quats0, obj_id, k)
    g = Gaussians(means=np.concatenate(parts["means"]), quats=np.concatenate(parts["quats"]),
                  scales=np.concatenate(parts["scales"]), opacities=np.concatenate(parts["opacities"]),
                  colors=np.concatenate(parts["colors"]), object_ids=np.concatenate(parts["ids"]))
    motion = Motion.rigid(np.concatenate(parts["nodes"]), rotations, translations,
                          node_objects=np.arange(1, len(instances) + 1))
    text = prompt if prompt is not None else getattr(plan, "text", None)
    subs = tuple(sub.as_triple() for sub in plan_substitutions(plan))
    return Scene4D(g, motion, objects, config.fps, cameras,
                   provenance=Provenance(text, int(seed), "procedural", "none", substitutions=subs),
                   background=setting.background)
