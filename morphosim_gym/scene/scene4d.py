"""`Scene4D`: the editable 4D world state (canonical Gaussians + motion + objects + feature field)."""

from __future__ import annotations

import hashlib
import json
import math
import threading
from collections import OrderedDict
from dataclasses import asdict, dataclass, field, fields
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from .camera import Camera
from .features import FeatureDecoder
from .gaussians import Gaussians
from .motion import Motion, skin
from .sky import check_sky

__all__ = ["SceneObject", "Provenance", "Scene4D", "POSE_CACHE_SIZE", "POSE_CACHE_BYTES"]

POSE_CACHE_SIZE = 4     # posed Gaussians always kept per scene (by time), least recently used dropped first
POSE_CACHE_BYTES = 8 << 20
"""More times are kept while a scene's posed means and quats take at most this many bytes: a
4k-Gaussian scene (114 KB a time) keeps ~70 times, a whole 60-step episode at 10 Hz, so pooled
scenes are skinned once per time, not once per episode; a 200k-Gaussian scene keeps the 4."""
DRAWN_SUBSET = 0.25      # `drawn_at` gives a subset of the rows when at most this share is drawn


@dataclass(frozen=True)
class SceneObject:
    """An object of a scene.

    Attributes:
        id: the value this object's Gaussians carry in `object_ids` and renders in `instance`.
        name: the noun as written in the prompt (e.g. "sedan").
        category: the library category it was grounded to (e.g. "car").
        color: RGB in [0, 1] the object was asked to have, if any.
        dynamic: whether the object moves.
        role: "object", "background" (ground, water, sky...) or "agent".
        asset: the real asset its Gaussians came from ("source/id"), or None for a procedural one.
    """

    id: int
    name: str
    category: str
    color: tuple[float, float, float] | None = None
    dynamic: bool = False
    role: str = "object"
    asset: str | None = None

    def __post_init__(self) -> None:
        if isinstance(self.id, bool) or not isinstance(self.id, (int, np.integer)) or self.id < 0:
            raise ValueError(f"Expected a non-negative integer object id, found {self.id!r}")
        object.__setattr__(self, "id", int(self.id))
        if not isinstance(self.name, str) or not self.name.strip():
            raise ValueError(f"Expected a non-empty object name, found {self.name!r}")
        if self.role not in ("object", "background", "agent"):
            raise ValueError(f"Expected role 'object', 'background' or 'agent', found {self.role!r}")
        if self.color is not None:
            c = tuple(float(x) for x in self.color)
            if len(c) != 3 or not all(0.0 <= x <= 1.0 for x in c):
                raise ValueError(f"Expected color as 3 numbers in [0, 1], found {self.color!r}")
            object.__setattr__(self, "color", c)

    def to_dict(self) -> dict:
        """JSON-friendly form (`asset` only when set, so procedural scenes save as before)."""
        d = asdict(self)
        if d["asset"] is None:
            del d["asset"]
        return d


@dataclass(frozen=True)
class Provenance:
    """Where a scene came from: the prompt and seed, which backends, and the edits applied since."""

    prompt: str | None = None
    seed: int | None = None
    generator: str = "unknown"
    reconstruction: str = "none"
    edits: tuple[str, ...] = ()
    substitutions: tuple[tuple[str, str, float | None], ...] = ()   # (asked noun, chosen, similarity)

    def to_dict(self) -> dict:
        """JSON-friendly form (`substitutions` only when there are some)."""
        d = asdict(self)
        d["edits"] = list(self.edits)
        if self.substitutions:
            d["substitutions"] = [list(x) for x in self.substitutions]
        else:
            del d["substitutions"]
        return d


@dataclass(eq=False)
class Scene4D:
    """A dynamic scene of 3D Gaussians.

    Attributes:
        gaussians: canonical Gaussians (numpy), with `object_ids` and, when a feature field was
            distilled, latent `features` [N, D].
        motion: node poses over T frames and the skinning of the Gaussians to them.
        objects: the scene's objects; `gaussians.object_ids` refer to their ids.
        fps: frames per second of `motion`.
        cameras: the generation camera, one per frame (or a single fixed one).
        decoders: feature-field decoders by encoder name.
        provenance: prompt, seed, backends and the edit history.
        background: RGB in [0, 1] shown where no Gaussian covers a pixel.
        parent: the scene this one was edited from (for `undo`), if any.
        sky: an equirectangular sky image [H, W, 3] in [0, 1] (see `scene.sky`) that `render` shows
            behind the Gaussians instead of `background`, or None.
        sensor: sensor effects the cameras record with, ((name, amount), ...) with name "noise",
            "blur" or "jpeg" and amount in (0, 1]; `render` ignores them, the env's `SensorEffects`
            wrapper applies them to the observations. () for a perfect sensor.

    Examples:
        >>> scene.at(1.0)            # world Gaussians 1 s into the clip (read-only)  # doctest: +SKIP
        >>> scene.centre()           # [3] what the generation camera looks at  # doctest: +SKIP
    """

    gaussians: Gaussians
    motion: Motion
    objects: tuple[SceneObject, ...]
    fps: float
    cameras: tuple[Camera, ...]
    decoders: Mapping[str, FeatureDecoder] = field(default_factory=dict)
    provenance: Provenance = field(default_factory=Provenance)
    background: tuple[float, float, float] = (0.0, 0.0, 0.0)
    parent: "Scene4D | None" = None
    sky: np.ndarray | None = None
    sensor: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.gaussians, Gaussians) or self.gaussians.is_torch:
            raise ValueError("Expected gaussians as a numpy-backed Gaussians, found "
                             f"{type(self.gaussians).__name__}")
        if not isinstance(self.motion, Motion):
            raise ValueError(f"Expected motion as a Motion, found {type(self.motion).__name__}")
        n = len(self.gaussians)
        if self.motion.num_gaussians != n:
            raise ValueError(f"Expected motion skinning for {n} Gaussians, found {self.motion.num_gaussians}")
        self.objects = tuple(self.objects)
        ids = [o.id for o in self.objects]
        if len(set(ids)) != len(ids):
            raise ValueError(f"Expected unique object ids, found {ids}")
        if self.gaussians.object_ids is None:
            self.gaussians = self.gaussians.replace(object_ids=np.full(n, -1, dtype=np.int32))
        present = np.unique(self.gaussians.object_ids)
        unknown = sorted(set(present.tolist()) - set(ids) - {-1})
        if unknown:
            raise ValueError(f"Expected gaussians.object_ids to name objects {ids}, found unknown ids {unknown}")
        fps = float(self.fps)
        if not (math.isfinite(fps) and fps > 0):
            raise ValueError(f"Expected fps > 0, found {self.fps}")
        self.fps = fps
        if isinstance(self.cameras, Camera):
            self.cameras = (self.cameras,)
        self.cameras = tuple(self.cameras)
        if len(self.cameras) not in (1, self.motion.num_frames) or not all(isinstance(c, Camera) for c in self.cameras):
            raise ValueError(f"Expected 1 or {self.motion.num_frames} Cameras, found {len(self.cameras)}")
        self.decoders = dict(self.decoders)
        for name, dec in self.decoders.items():
            if not isinstance(dec, FeatureDecoder):
                raise ValueError(f"Expected decoders[{name!r}] to be a FeatureDecoder, found {type(dec).__name__}")
            if dec.in_dim != self.gaussians.feature_dim:
                raise ValueError(f"Expected decoder {name!r} to take {self.gaussians.feature_dim}-d features, "
                                 f"found input width {dec.in_dim}")
        bg = tuple(float(x) for x in self.background)
        if len(bg) != 3 or not all(0.0 <= x <= 1.0 for x in bg):
            raise ValueError(f"Expected background as 3 numbers in [0, 1], found {self.background!r}")
        self.background = bg
        if self.sky is not None:
            self.sky = check_sky(self.sky)
        self.sensor = _check_sensor(self.sensor)
        _freeze(self.gaussians)
        for arr in self.motion.arrays().values():
            arr.setflags(write=False)
        self._poses: OrderedDict[Any, Gaussians] = OrderedDict()   # frame index (or ("drawn", it)) -> posed (LRU)
        self._pose_bytes = 0                                          # bytes of their own arrays
        self._poses_lock = threading.Lock()
        self._shown: OrderedDict[int, dict | None] = OrderedDict()    # frame -> its drawn rows (`_drawn_rows`)
        self._hash: str | None = None

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.pop("_poses_lock")
        state["_poses"] = OrderedDict()          # caches, rebuilt on demand
        state["_shown"] = OrderedDict()
        state["_pose_bytes"] = 0
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self.__dict__.setdefault("_pose_bytes", 0)     # a pickle from before the byte budget
        self.__dict__.setdefault("_shown", OrderedDict())
        self._poses_lock = threading.Lock()

    # -------------------------------------------------------------- time
    @property
    def num_frames(self) -> int:
        """T, the number of frames the motion is defined on."""
        return self.motion.num_frames

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame, (T - 1) / fps."""
        return (self.num_frames - 1) / self.fps

    @property
    def times(self) -> np.ndarray:
        """[T] the time of each frame, seconds."""
        return np.arange(self.num_frames) / self.fps

    def frame_index(self, t: float) -> float:
        """Fractional frame index of time `t`; `ValueError` outside [0, duration]."""
        try:
            tf = float(t)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"Expected t as a number of seconds, found {t!r}") from exc
        if not math.isfinite(tf) or tf < -1e-9 or tf > self.duration + 1e-9:
            raise ValueError(f"Expected t in [0, {self.duration:.4g}] s (the clip), found {t!r}")
        return min(max(tf, 0.0), self.duration) * self.fps

    def at(self, t: float = 0.0) -> Gaussians:
        """World Gaussians at time `t` seconds, node poses interpolated between frames (slerp for
        rotations).

        The arrays are read-only (`flags.writeable` False) and shared: the last `POSE_CACHE_SIZE`
        times asked are kept, so callers may interleave times freely at no extra skinning cost.
        Use `.numpy()` on the result for a copy of one's own to modify. Gaussians not drawn at `t`
        (`drawn`) are here with opacity 0; `drawn_at` leaves them out.
        """
        frame = self.frame_index(t)
        cached = self._cached(frame)
        if cached is not None:
            return cached
        c = self.gaussians
        means, quats = self.motion.apply(c.means, c.quats, frame)
        rows = None if self.motion.shown is None else self._drawn_rows(frame)
        return self._cache(frame, Gaussians._trusted(
            means=_frozen(means), quats=_frozen(quats), scales=c.scales,
            opacities=c.opacities if rows is None else rows["opacities"], colors=c.colors, features=c.features,
            object_ids=c.object_ids))

    def drawn(self, t: float = 0.0) -> np.ndarray | None:
        """[N] bool: the Gaussians drawn at time `t` (`Motion.shown`), or None when all are."""
        if self.motion.shown is None:
            self.frame_index(t)                   # (checks t)
            return None
        rows = self._drawn_rows(self.frame_index(t))
        return None if rows is None else rows["mask"]

    def drawn_at(self, t: float = 0.0) -> Gaussians:
        """The Gaussians drawn at time `t`, posed: only the drawn rows (skinned alone, cached like
        `at`) when they are at most `DRAWN_SUBSET` of the scene, else `at(t)` itself (whose rows not
        drawn have opacity 0: copying most rows costs more than drawing nothing there). What a
        renderer needs."""
        if self.motion.shown is None:             # the usual scene: everything, every frame
            return self.at(t)
        frame = self.frame_index(t)
        rows = self._drawn_rows(frame)
        if rows is None or len(rows["rows"]) > DRAWN_SUBSET * len(self.gaussians):
            return self.at(t)                     # (its undrawn rows have opacity 0)
        cached = self._cached(("drawn", frame))
        if cached is not None:
            return cached
        c, m, index = self.gaussians, self.motion, rows["rows"]
        if "parts" not in rows:                   # the drawn rows' fixed arrays, once per frame kept
            rows["parts"] = {k: None if getattr(c, k) is None else _frozen(getattr(c, k)[index])
                             for k in ("means", "quats", "scales", "opacities", "colors", "features", "object_ids")}
            rows["skin"] = (m.skin_nodes[index], m.skin_weights[index])
        parts = dict(rows["parts"])
        rot, trans = m.node_poses(frame)
        means, quats = skin(parts.pop("means"), parts.pop("quats"), *rows["skin"], rot, trans)
        return self._cache(("drawn", frame), Gaussians._trusted(means=_frozen(means), quats=_frozen(quats), **parts))

    def _drawn_rows(self, frame: float) -> dict | None:
        """Which rows are drawn at the frame nearest `frame` (`mask`, `rows`) and their opacities for
        `at` (0 where not drawn), kept for the last `POSE_CACHE_SIZE` frames asked (None when every
        Gaussian is drawn); `drawn_at` adds the drawn rows' arrays."""
        key = self.motion.nearest_frame(frame)
        with self._poses_lock:
            if key in self._shown:
                self._shown.move_to_end(key)
                return self._shown[key]
        mask = self.motion.drawn(key)
        out = None
        if mask is not None:
            opacities = self.gaussians.opacities
            out = {"mask": _frozen(mask), "rows": np.flatnonzero(mask),
                   "opacities": _frozen(np.where(mask, opacities, 0).astype(opacities.dtype))}
        with self._poses_lock:
            self._shown[key] = out
            while len(self._shown) > POSE_CACHE_SIZE:
                self._shown.popitem(last=False)
        return out

    def _cached(self, key: Any) -> Gaussians | None:
        with self._poses_lock:
            g = self._poses.get(key)
            if g is not None:
                self._poses.move_to_end(key)
            return g

    def _cache(self, key: Any, g: Gaussians) -> Gaussians:
        with self._poses_lock:
            if key not in self._poses:
                self._poses[key] = g
                self._pose_bytes += _posed_bytes(g, self.gaussians)
            while len(self._poses) > POSE_CACHE_SIZE and self._pose_bytes > POSE_CACHE_BYTES:
                self._pose_bytes -= _posed_bytes(self._poses.popitem(last=False)[1], self.gaussians)
        return g

    def centre(self, t: float = 0.0) -> np.ndarray:
        """[3] the scene centre at time t: where the generation camera looks, the point on its
        optical axis nearest the mean of the non-background objects' Gaussians (or at the median
        depth of all Gaussians if there are none). Orbits, novel views and camera edits turn about it."""
        cam = self.camera_at(t)
        g = self.at(t)
        drawn = self.drawn(t)
        shown = np.ones(len(g), bool) if drawn is None else drawn
        fg = np.isin(g.object_ids, [o.id for o in self.objects if o.role != "background"]) & shown
        pts = g.means[fg] if fg.any() else g.means[shown]
        if len(pts) == 0:
            return cam.position + cam.forward
        depth = float(np.median((pts - cam.position) @ cam.forward)) if not fg.any() else \
            float((pts.mean(0) - cam.position) @ cam.forward)
        return cam.position + max(depth, 1e-3) * cam.forward

    # ------------------------------------------------------------- cameras
    @property
    def camera(self) -> Camera:
        """The generation camera (at t = 0)."""
        return self.cameras[0]

    def camera_at(self, t: float) -> Camera:
        """The generation camera at time `t` (the nearest frame's; fixed cameras are constant)."""
        if len(self.cameras) == 1:
            self.frame_index(t)
            return self.cameras[0]
        return self.cameras[int(round(self.frame_index(t)))]

    # ------------------------------------------------------------- objects
    def object(self, key: int | str) -> SceneObject:
        """The object with this id, or this name (or category); `ValueError` listing the objects otherwise."""
        for o in self.objects:
            if (isinstance(key, (int, np.integer)) and o.id == key) or (isinstance(key, str) and key in (o.name, o.category)):
                return o
        raise ValueError(f"Expected an object of the scene, found {key!r}; objects: {self.object_names}")

    @property
    def object_names(self) -> list[str]:
        """Names of the objects, in order."""
        return [o.name for o in self.objects]

    @property
    def id_to_name(self) -> dict[int, str]:
        """Object id -> name."""
        return {o.id: o.name for o in self.objects}

    def object_center(self, key: int | str, t: float = 0.0) -> np.ndarray:
        """[3] mean position of an object's Gaussians drawn at time t (all of them when none is)."""
        obj = self.object(key)
        g = self.at(t)
        sel = g.object_ids == obj.id
        if not np.any(sel):
            raise ValueError(f"Expected Gaussians for object {obj.name!r}, found none")
        return self.rows_center(np.flatnonzero(sel), t)

    def rows_center(self, rows: np.ndarray, t: float = 0.0) -> np.ndarray:
        """[3] mean position at time t of the Gaussians `rows` that are drawn then (all of them
        when none is): an object's centre, an env's target."""
        drawn = self.drawn(t)
        if drawn is not None and drawn[rows].any():
            rows = rows[drawn[rows]]
        return self.at(t).means[rows].mean(axis=0, dtype=np.float64)

    # ------------------------------------------------------------ editing
    @property
    def history(self) -> tuple[str, ...]:
        """The edits applied since generation, in order."""
        return self.provenance.edits

    def derive(self, edit: str | None = None, **changes: Any) -> "Scene4D":
        """A new scene with some fields replaced; `edit` is appended to the history and this scene
        becomes the new one's parent (so `undo` returns it)."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values.update(changes)
        if edit is not None:
            prov = values["provenance"]
            values["provenance"] = Provenance(prov.prompt, prov.seed, prov.generator, prov.reconstruction,
                                              prov.edits + (edit,), prov.substitutions)
            values["parent"] = self
        return Scene4D(**values)

    def undo(self) -> "Scene4D":
        """The scene before the last edit; `ValueError` if there is none."""
        if self.parent is None:
            raise ValueError("Expected an edited scene to undo, found a scene with no edit history")
        return self.parent

    # -------------------------------------------------------------- identity
    def content_hash(self) -> str:
        """SHA-256 (hex) of everything that defines the scene (not its parent)."""
        if self._hash is None:
            h = hashlib.sha256()
            for name, arr in sorted(self.arrays().items()):
                h.update(name.encode())
                h.update(str(arr.dtype).encode() + str(arr.shape).encode())
                h.update(np.ascontiguousarray(arr).tobytes())
            h.update(json.dumps(self.metadata(), sort_keys=True).encode())
            self._hash = h.hexdigest()
        return self._hash

    def arrays(self) -> dict[str, np.ndarray]:
        """All arrays of the scene by a flat name (what `save_scene` writes)."""
        g = self.gaussians
        out: dict[str, np.ndarray] = {f"gaussians/{k}": getattr(g, k)
                                      for k in ("means", "quats", "scales", "opacities", "colors", "object_ids")}
        if g.features is not None:
            out["gaussians/features"] = g.features
        out.update({f"motion/{k}": v for k, v in self.motion.arrays().items()})
        for name, dec in self.decoders.items():
            out.update({f"decoders/{name}/{k}": v for k, v in dec.arrays().items()})
        if self.sky is not None:
            out["sky"] = self.sky
        return out

    def metadata(self) -> dict:
        """All non-array fields, JSON-friendly."""
        return {
            "objects": [o.to_dict() for o in self.objects],
            "fps": self.fps,
            "cameras": [c.to_dict() for c in self.cameras],
            "decoders": {name: {"normalize": d.normalize} for name, d in self.decoders.items()},
            "provenance": self.provenance.to_dict(),
            "background": list(self.background),
            **({"sensor": [list(e) for e in self.sensor]} if self.sensor else {}),   # absent: old hashes hold
        }

    def __repr__(self) -> str:
        return (f"Scene4D(gaussians={len(self.gaussians)}, frames={self.num_frames}, fps={self.fps:g}, "
                f"objects={self.object_names}, edits={len(self.history)})")


SENSOR_NAMES = ("noise", "blur", "jpeg")


def _check_sensor(effects: object) -> tuple[tuple[str, float], ...]:
    out = []
    for e in tuple(effects or ()):  # type: ignore[arg-type]
        if not (isinstance(e, (tuple, list)) and len(e) == 2 and e[0] in SENSOR_NAMES):
            raise ValueError(f"Expected sensor effects as (name, amount) with name in {SENSOR_NAMES}, found {e!r}")
        amount = float(e[1])
        if not (math.isfinite(amount) and 0.0 < amount <= 1.0):
            raise ValueError(f"Expected a sensor effect amount in (0, 1], found {e[1]!r}")
        out.append((str(e[0]), amount))
    return tuple(out)


def _freeze(g: Gaussians) -> None:
    for name in ("means", "quats", "scales", "opacities", "colors", "features", "object_ids"):
        arr = getattr(g, name)
        if isinstance(arr, np.ndarray):
            arr.setflags(write=False)


def objects_from_dicts(items: Iterable[Mapping[str, Any]]) -> tuple[SceneObject, ...]:
    """SceneObjects from their `to_dict` forms."""
    out = []
    for d in items:
        d = dict(d)
        if d.get("color") is not None:
            d["color"] = tuple(d["color"])
        out.append(SceneObject(**d))
    return tuple(out)


def provenance_from_dict(d: Mapping[str, Any]) -> Provenance:
    """Inverse of `Provenance.to_dict`."""
    d = dict(d)
    d["edits"] = tuple(d.get("edits", ()))
    d["substitutions"] = tuple(tuple(x) for x in d.get("substitutions", ()))
    return Provenance(**d)


def cameras_from_dicts(items: Sequence[Mapping[str, Any]]) -> tuple[Camera, ...]:
    """Cameras from their `to_dict` forms."""
    return tuple(Camera.from_dict(dict(c)) for c in items)


def _frozen(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def _posed_bytes(g: Gaussians, own: Gaussians) -> int:
    """Bytes a pose-cache entry holds of its own (its arrays that are not the scene's `own`)."""
    return sum(int(a.nbytes) for f in fields(g) if (a := getattr(g, f.name)) is not None
               and a is not getattr(own, f.name))
