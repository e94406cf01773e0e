"""`SceneWorld`: the world half of an env (dm_control's "physics"): a `Scene4D` at a time, the
target object, and small named accessors the tasks read.

Scene time follows the control rate: `t = step / control_hz`, interpolated between the
clip's frames by `Scene4D.at`. The world never renders; the env does.
"""

from __future__ import annotations

from typing import Optional
from weakref import WeakKeyDictionary

import numpy as np

from morphosim_gym.scene import Camera, Gaussians, Scene4D, SceneObject

__all__ = ["SceneWorld"]

_TARGET_POSITIONS: "WeakKeyDictionary[Scene4D, dict]" = WeakKeyDictionary()
"""Per scene, (target id, t) -> the target's mean position: a function of the (immutable) scene,
so every episode and every env on a pooled scene computes it once per time."""
_POSITIONS_PER_SCENE = 4096      # entries kept per scene (times of a few episodes' clocks)


class SceneWorld:
    """A scene, its target and the episode clock.

    Args:
        scene: the episode's scene (after any reset edits).
        target: the target object (one of `scene.objects`).

    Attributes:
        t: scene time in seconds.
        target_radius: the target's bounding radius at t = 0 (metres), from the scene as it
            was at reset (kept through later edits so success distances do not jump).
    """

    def __init__(self, scene: Scene4D, target: SceneObject) -> None:
        self.t = 0.0
        self.target = target
        self._scene = self._original = scene
        self._index = self._original_index = np.flatnonzero(scene.gaussians.object_ids == target.id)
        if self._index.size == 0:
            raise ValueError(f"Expected Gaussians for the target {target.name!r}, found none")
        g0 = scene.at(0.0)
        pts = g0.means[self._index].astype(np.float64)
        c = pts.mean(axis=0)
        self.target_radius = float(np.linalg.norm(pts - c, axis=1).max())
        self.target_floor = float(pts[:, 2].min())
        self.focus = scene.centre(0.0)
        self.extent = float(np.linalg.norm(self.focus - scene.camera.position))
        self.ground_z = 0.0

    # ------------------------------------------------------------ the scene
    @property
    def scene(self) -> Scene4D:
        """The current scene (edits replace it)."""
        return self._scene

    def set_scene(self, scene: Scene4D) -> None:
        """Replace the scene (after an edit); the target keeps its id and may vanish (removed)."""
        self._scene = scene
        self._index = np.flatnonzero(scene.gaussians.object_ids == self.target.id)

    @property
    def generation_camera(self) -> Camera:
        """The scene's generation camera."""
        return self._scene.camera

    @property
    def duration(self) -> float:
        """Seconds of the clip."""
        return self._scene.duration

    def gaussians(self, t: Optional[float] = None) -> Gaussians:
        """World Gaussians drawn at time t (default now), to render; cached, not to be modified."""
        return self._scene.drawn_at(self.t if t is None else t)

    # ------------------------------------------------------------ the target
    @property
    def target_present(self) -> bool:
        """Whether the target still has Gaussians (an edit may have removed it)."""
        return self._index.size > 0

    def target_position(self, t: Optional[float] = None) -> Optional[np.ndarray]:
        """[3] mean position of the target's Gaussians at time t (default now), or None if removed."""
        if self._index.size == 0:
            return None
        t = self.t if t is None else float(t)
        known = _TARGET_POSITIONS.setdefault(self._scene, {})
        key = (self.target.id, t)
        pos = known.get(key)
        if pos is None:
            pos = self._scene.rows_center(self._index, t)
            if len(known) < _POSITIONS_PER_SCENE:
                known[key] = pos
        return pos.copy()

    def target_path(self, n: int = 25) -> np.ndarray:
        """[n, 3] target positions at n evenly spaced times over the clip (in the scene as it was
        before any edit if an edit removed the target)."""
        scene = self._scene if self._index.size else self._original
        index = self._index if self._index.size else self._original_index
        times = np.linspace(0.0, self.duration, n)
        out = np.array([scene.rows_center(index, float(t)) for t in times])
        return out

