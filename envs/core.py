"""`MorphoSimEnv`: the Gymnasium env that composes a world (`SceneWorld`), a rig and a task.

The three registered envs (`TrackEnv`, `ReachEnv`, `FindEnv`) are thin subclasses that fix
the task kind, document it, and give typed constructor keyword arguments; everything else
lives here: scene sources and pools, reset options, edits, rendering, observations, info.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from contextlib import contextmanager
from typing import Any, Mapping, Optional, Sequence

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from morphosim_gym.errors import CommandError, EditError
from morphosim_gym.render.api import render as render_scene
from morphosim_gym.rig import AGENT_OBJECT_ID
from morphosim_gym.scene import Camera, Gaussians, Scene4D
from morphosim_gym.tasks import Task, TaskView, check_camera_override, describe_object, make_task
from morphosim_gym.tasks.spec import SceneRequest

from .world import SceneWorld

__all__ = ["MorphoSimEnv", "RESET_OPTION_KEYS", "SceneSource"]

RESET_OPTION_KEYS = ("prompt", "scene_seed", "target", "edits", "camera", "on_edit_error")
ON_EDIT_ERROR = ("raise", "skip")


@contextmanager
def _numba_threads(n: Optional[int]):
    """Run the enclosed numba kernels with `n` threads (numba's setting is per calling thread), then
    restore the previous count; None leaves it alone."""
    if n is None:
        yield
        return
    import numba

    old = numba.get_num_threads()
    numba.set_num_threads(min(int(n), numba.config.NUMBA_NUM_THREADS))
    try:
        yield
    finally:
        numba.set_num_threads(old)


def _check_int(value: Any, name: str, low: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) < low:
        raise ValueError(f"Expected {name} as an integer >= {low}, found {value!r}")
    return int(value)


class SceneSource:
    """Scenes by (prompt, seed) through a `MorphoSim`, with an in-memory LRU cache.

    With `reconstruction="oracle"` (the envs' default) `MorphoSim.generate` composes the ground
    truth directly, without rendering the clip frames that path discards.
    """

    def __init__(self, sim: Any, cache_size: int = 32) -> None:
        self.sim = sim
        self.cache_size = int(cache_size)
        self._cache: OrderedDict[tuple[str, int], Scene4D] = OrderedDict()

    def get(self, prompt: str, seed: int) -> Scene4D:
        """The scene of a prompt and seed (cached)."""
        key = (prompt, int(seed))
        if key in self._cache:
            self._cache.move_to_end(key)
            return self._cache[key]
        scene = self._generate(prompt, int(seed))
        self._cache[key] = scene
        while len(self._cache) > self.cache_size:
            self._cache.popitem(last=False)
        return scene

    def _generate(self, prompt: str, seed: int) -> Scene4D:
        return self.sim.generate(prompt, seed=seed)


class MorphoSimEnv(gym.Env):
    """Base class of the MorphoSim envs; see `TrackEnv`, `ReachEnv`, `FindEnv` for the documented
    envs and their arguments."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}
    task_kind = ""

    def __init__(
        self,
        *,
        task: Any = None,
        prompt: Optional[str] = None,
        target: Optional[str] = None,
        scene_seed: Optional[int] = None,
        scene_pool: Optional[int] = None,
        pool_seed: int = 0,
        width: int = 84,
        height: int = 84,
        depth: bool = False,
        segmentation: bool = False,
        cameras: Optional[Sequence[str]] = None,
        control_hz: float = 10.0,
        detail: float = 0.35,
        reconstruction: str = "oracle",
        render_agent: Optional[bool] = None,
        terminate_on_success: bool = False,
        on_edit_error: str = "raise",
        render_mode: Optional[str] = None,
        render_width: int = 256,
        render_height: int = 256,
        render_threads: Optional[int] = 1,
        sim: Any = None,
        task_params: Optional[Mapping[str, float]] = None,
    ) -> None:
        # ---------------------------------------------------------- validation
        for name, v in (("width", width), ("height", height), ("render_width", render_width),
                        ("render_height", render_height)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 8 <= int(v) <= 1024:
                raise ValueError(f"Expected {name} as an integer in [8, 1024], found {v!r}")
        if not (isinstance(control_hz, (int, float)) and math.isfinite(control_hz) and 0.5 <= control_hz <= 100):
            raise ValueError(f"Expected control_hz in [0.5, 100], found {control_hz!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"Expected render_mode in {self.metadata['render_modes']} or None, found {render_mode!r}")
        if on_edit_error not in ON_EDIT_ERROR:
            raise ValueError(f"Expected on_edit_error in {ON_EDIT_ERROR}, found {on_edit_error!r}")
        if prompt is not None and (not isinstance(prompt, str) or not prompt.strip()):
            raise ValueError(f"Expected prompt as a non-empty string, found {prompt!r}")
        if scene_seed is not None:
            scene_seed = _check_int(scene_seed, "scene_seed")
        if scene_pool is not None:
            scene_pool = _check_int(scene_pool, "scene_pool", 1)
        pool_seed = _check_int(pool_seed, "pool_seed")
        if render_threads is not None:
            render_threads = _check_int(render_threads, "render_threads", 1)
        self._render_threads = render_threads

        # ---------------------------------------------------------- parts
        self._task: Task = make_task(task if task is not None else self.task_kind, **dict(task_params or {}))
        if self._task.kind != self.task_kind:
            raise ValueError(f"Expected a task of kind {self.task_kind!r} for this env, found {self._task.kind!r}")
        self._rig = self._task.make_rig()
        if sim is None:
            from morphosim_gym.generate.compose import GenerationConfig
            from morphosim_gym.pipeline import MorphoSim

            sim = MorphoSim(reconstruction=reconstruction, generation=GenerationConfig(detail=float(detail)))
        self._sim = sim
        self._source = SceneSource(sim)
        cams = tuple(cameras) if cameras is not None else self._task.default_cameras
        if not cams or len(set(cams)) != len(cams):
            raise ValueError(f"Expected one or more distinct camera names, found {cameras!r}")
        for c in cams:
            if c not in self._rig.camera_names:
                raise ValueError(f"Expected cameras of the rig {self._rig.camera_names}, found {c!r}")
        self._obs_cameras = cams
        self._render_cams = cams + tuple(c for c in (self._task.task_camera,) if c not in cams)
        self._width, self._height = int(width), int(height)
        self._depth, self._segmentation = bool(depth), bool(segmentation)
        self._dt = 1.0 / float(control_hz)
        self._control_hz = float(control_hz)
        self._render_agent = self._task.render_agent if render_agent is None else bool(render_agent)
        self._terminate_on_success = bool(terminate_on_success)
        self._on_edit_error = on_edit_error
        self.render_mode = render_mode
        self._render_size = (int(render_width), int(render_height))
        self._prompt, self._target_name, self._scene_seed = prompt, target, scene_seed
        self.metadata = dict(self.metadata, render_fps=self._control_hz)

        # ---------------------------------------------------------- spaces
        obs: dict[str, spaces.Space] = {}
        for i, name in enumerate(cams):
            sfx = "" if i == 0 else f"_{name}"
            obs["rgb" + sfx] = spaces.Box(0, 255, (self._height, self._width, 3), np.uint8)
            if self._depth:
                obs["depth" + sfx] = spaces.Box(0.0, np.inf, (self._height, self._width), np.float32)
            if self._segmentation:
                obs["segmentation" + sfx] = spaces.Box(-1, AGENT_OBJECT_ID, (self._height, self._width), np.int32)
        low, high = self._rig.proprio_bounds()
        obs["proprio"] = spaces.Box(low, high, (self._rig.proprio_dim,), np.float32)
        self.observation_space = spaces.Dict(obs)
        self.action_space = spaces.Box(-1.0, 1.0, (self._rig.action_dim,), np.float32)

        # ---------------------------------------------------------- scene pool
        self._pool: list[tuple[SceneRequest, int]] = []
        if scene_pool is not None:
            rng = np.random.default_rng([pool_seed, 0x5EED])
            for _ in range(scene_pool):
                req = self._request(rng)
                seed = self._scene_seed if self._scene_seed is not None else int(rng.integers(2 ** 31 - 1))
                self._pool.append((req, seed))
            self._source.cache_size = max(self._source.cache_size, scene_pool)
            for req, seed in self._pool:                    # pre-build: resets do not generate
                self._source.get(req.prompt, seed)

        self._world: Optional[SceneWorld] = None
        self._step_count = 0
        self._edits: list[str] = []
        self._edit_errors: list[str] = []
        self._episode: dict[str, Any] = {}
        self._last_view: Optional[TaskView] = None
        self._last_cams: dict[str, Camera] = {}

    # ================================================================== public
    @property
    def task(self) -> Task:
        """The task (reward, success, scene distribution)."""
        return self._task

    @property
    def rig(self) -> Any:
        """The MuJoCo rig (kinematics, cameras)."""
        return self._rig

    @property
    def world(self) -> SceneWorld:
        """The current episode's world (scene, time, target)."""
        if self._world is None:
            raise RuntimeError("Expected reset() before using the world, found no episode")
        return self._world

    @property
    def scene(self) -> Scene4D:
        """The current (possibly edited) scene."""
        return self.world.scene

    @property
    def dt(self) -> float:
        """Seconds of scene time per step (1 / control_hz)."""
        return self._dt

    # ================================================================== reset
    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[dict, dict]:
        super().reset(seed=seed)
        with _numba_threads(self._render_threads):
            return self._reset(self._check_options(options))

    def _reset(self, opts: dict) -> tuple[dict, dict]:
        rng = self.np_random
        # ---- which scene
        target_name = opts.get("target", self._target_name)
        if "prompt" in opts:
            scene_seed = opts.get("scene_seed", self._scene_seed)
            if scene_seed is None:
                scene_seed = int(rng.integers(2 ** 31 - 1))
            request = SceneRequest(opts["prompt"], target_name or "", "")
        elif self._pool and "scene_seed" not in opts:
            request, scene_seed = self._pool[int(rng.integers(len(self._pool)))]
        else:
            request = self._request(rng)
            scene_seed = opts.get("scene_seed", self._scene_seed)
            if scene_seed is None:
                scene_seed = int(rng.integers(2 ** 31 - 1))
        scene = self._source.get(request.prompt, int(scene_seed))
        target = self._task.resolve_target(scene, target_name or request.target or None)
        description = request.target_description if request.target_description and not target_name \
            else describe_object(target)
        # ---- edits before the episode
        policy = opts.get("on_edit_error", self._on_edit_error)
        self._edits, self._edit_errors = [], []
        world = SceneWorld(scene, target)          # geometry (target size, focus) from the unedited scene
        for text in opts.get("edits", ()):
            scene = self._apply_edit(scene, text, policy)
        world.set_scene(scene)
        # ---- world, rig, task
        self._world = world
        self._step_count = 0
        self._task.initialize_episode(self._world, self._rig, rng, opts.get("camera", {}))
        self._episode = {"prompt": request.prompt, "scene_seed": int(scene_seed), "target": target.name,
                         "target_id": target.id, "instruction": self._task.instruction(description),
                         "edit_policy": policy}
        views = self._render(self._world.t)
        metrics = dict(self._task.measure(self._world, self._rig, self._last_view), **self._task.reset_metrics())
        return self._observation(views), self._info(False, {}, metrics)

    def _request(self, rng: np.random.Generator) -> SceneRequest:
        if self._prompt is not None:
            return SceneRequest(self._prompt, self._target_name or "", "")
        return self._task.sample_scene(rng)

    def _check_options(self, options: Optional[dict]) -> dict:
        if options is None:
            return {}
        if not isinstance(options, Mapping):
            raise ValueError(f"Expected options as a dict, found {type(options).__name__}")
        unknown = set(options) - set(RESET_OPTION_KEYS)
        if unknown:
            raise ValueError(f"Expected option keys in {list(RESET_OPTION_KEYS)}, found unknown {sorted(unknown)}")
        out = dict(options)
        if out.get("prompt") is None:
            out.pop("prompt", None)
        elif not isinstance(out["prompt"], str) or not out["prompt"].strip():
            raise ValueError(f"Expected options['prompt'] as a non-empty string, found {out['prompt']!r}")
        if out.get("scene_seed") is None:
            out.pop("scene_seed", None)
        else:
            out["scene_seed"] = _check_int(out["scene_seed"], "options['scene_seed']")
        if out.get("target") is None:
            out.pop("target", None)
        elif not isinstance(out["target"], str):
            raise ValueError(f"Expected options['target'] as an object name, found {out['target']!r}")
        edits = out.get("edits", ())
        if isinstance(edits, str):
            edits = [edits]
        if edits is None:
            edits = ()
        if not isinstance(edits, (list, tuple)) or not all(isinstance(e, str) and e.strip() for e in edits):
            raise ValueError(f"Expected options['edits'] as a list of edit commands (strings), found {edits!r}")
        out["edits"] = tuple(edits)
        out["camera"] = check_camera_override(out.get("camera"))
        if "on_edit_error" in out and out["on_edit_error"] not in ON_EDIT_ERROR:
            raise ValueError(f"Expected options['on_edit_error'] in {ON_EDIT_ERROR}, found {out['on_edit_error']!r}")
        return out

    # ================================================================== edits
    def _apply_edit(self, scene: Scene4D, text: str, policy: str) -> Scene4D:
        edit = getattr(self._sim, "edit", None)
        if edit is None:
            raise NotImplementedError("Expected a MorphoSim with sim.edit(scene, text) (the scene editor), found "
                                      "none in this build")
        try:
            new = edit(scene, text)
        except (EditError, CommandError) as exc:
            if policy == "skip":
                self._edit_errors.append(f"{text}: {exc}")
                return scene
            try:
                err = type(exc)(f"Edit {text!r} failed: {exc} (pass on_edit_error='skip' to go on without it)")
            except Exception:  # an error type with a different constructor: raise it as it is
                raise exc
            raise err from exc
        self._edits.append(text)
        return new

    def perturb(self, text: str) -> bool:
        """Apply a language edit to the scene now; the observation from the next step shows it.

        Returns True if the edit was applied, False if it failed and the env (or the episode's
        reset options) say `on_edit_error="skip"`; otherwise a failed edit raises
        `ms.EditError` / `ms.CommandError` and the scene stays as it was.
        """
        if not isinstance(text, str) or not text.strip():
            raise ValueError(f"Expected an edit command (a non-empty string), found {text!r}")
        world = self.world
        before = world.scene
        new = self._apply_edit(before, text, self._episode.get("edit_policy", self._on_edit_error))
        if new is before:
            return False
        world.set_scene(new)
        return True

    # ================================================================== step
    def step(self, action: Any) -> tuple[dict, float, bool, bool, dict]:
        a = self._check_action(action)
        with _numba_threads(self._render_threads):
            return self._step(a)

    def _step(self, a: np.ndarray) -> tuple[dict, float, bool, bool, dict]:
        world = self.world
        self._rig.apply(a, self._dt)
        self._step_count += 1
        world.t = min(self._step_count * self._dt, world.duration)
        views = self._render(world.t)
        ev = self._task.evaluate(world, self._rig, self._last_view, a)
        terminated = bool(self._terminate_on_success and ev.terminate)
        truncated = bool(world.t >= world.duration - 1e-9)
        info = self._info(ev.success, ev.terms, ev.metrics)
        return self._observation(views), float(ev.reward), terminated, truncated, info

    def _check_action(self, action: Any) -> np.ndarray:
        try:
            a = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"Expected an action of shape {self.action_space.shape}, found {action!r}") from exc
        if a.shape != self.action_space.shape:
            raise ValueError(f"Expected an action of shape {self.action_space.shape}, found shape {a.shape}")
        if not np.all(np.isfinite(a)):
            bad = np.flatnonzero(~np.isfinite(a)).tolist()
            raise ValueError(f"Expected finite action values, found NaN or inf at indices {bad}; the step was "
                             "not taken")
        return np.clip(a, -1.0, 1.0)          # out-of-range values are clipped to the Box

    # ================================================================== render
    def _cameras(self, names: Sequence[str], width: int, height: int) -> list[Camera]:
        return [self._rig.camera(n, width, height) for n in names]

    def _sources(self, t: float) -> list:
        g = [self._world.gaussians(t)]
        if self._render_agent:
            g.append(self._rig.gaussians())
        return g

    def _render(self, t: float) -> dict:
        cams = self._cameras(self._render_cams, self._width, self._height)
        out = render_scene(self._sources(t), cams, background=self._world.scene.background)
        self._last_cams = dict(zip(self._render_cams, cams))
        views = {name: (cams[i], out.rgb[i], out.depth[i], out.instance[i]) for i, name in enumerate(self._render_cams)}
        tc = views[self._task.task_camera]
        self._last_view = TaskView(tc[0], tc[3], t)
        return views

    def _observation(self, views: dict) -> dict:
        obs: dict[str, np.ndarray] = {}
        for i, name in enumerate(self._obs_cameras):
            cam, rgb, depth, inst = views[name]
            sfx = "" if i == 0 else f"_{name}"
            obs["rgb" + sfx] = (np.clip(rgb, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
            if self._depth:
                obs["depth" + sfx] = np.array(depth, dtype=np.float32)
            if self._segmentation:
                obs["segmentation" + sfx] = np.array(inst, dtype=np.int32)
        obs["proprio"] = self._rig.proprio()
        return obs

    def render(self) -> Optional[np.ndarray]:
        """An RGB frame [render_height, render_width, 3] uint8 of the first observation camera
        (with render_mode="rgb_array"; None otherwise)."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to gym.make")
            return None
        w, h = self._render_size
        cam = self._rig.camera(self._obs_cameras[0], w, h)
        with _numba_threads(self._render_threads):
            out = render_scene(self._sources(self.world.t), cam, background=self.world.scene.background)
        return out.rgb_uint8()

    # ================================================================== info
    def _info(self, success: bool, terms: Mapping[str, float], metrics: Mapping[str, Any]) -> dict:
        world = self.world
        cams = {}
        for name, c in self._last_cams.items():
            cams[name] = {"K": c.K, "world_to_camera": np.array(c.world_to_camera), "width": c.width,
                          "height": c.height}
        id_to_name = dict(world.scene.id_to_name)
        if self._render_agent:
            id_to_name[AGENT_OBJECT_ID] = "agent"
        info = {
            "success": bool(success),
            "target": self._episode["target"],
            "target_id": self._episode["target_id"],
            "target_position": world.target_position(),
            "instruction": self._episode["instruction"],
            "prompt": self._episode["prompt"],
            "scene_seed": self._episode["scene_seed"],
            "scene_id": world.scene.content_hash(),
            "edits": tuple(self._edits),
            "edit_errors": tuple(self._edit_errors),
            "t": float(world.t),
            "step": self._step_count,
            "cameras": cams,
            "id_to_name": id_to_name,
        }
        info.update({k: float(v) for k, v in terms.items()})
        info.update(metrics)
        return info

    def close(self) -> None:
        self._world = None
        super().close()
