"""`MorphoSimEnv`: the Gymnasium env that composes a world (`SceneWorld`), a rig and a task.

This module is the lifecycle glue: reset chooses a scene, applies the reset edits and lets the
task place the rig; step moves the rig, advances scene time, renders and hands the task camera's
view to the task. The parts live beside it: arguments (`config.EnvConfig`), reset options
(`options`), scene choice and pools (`scenes`), observations and actions (`spaces`),
edits (`edits`), numba threads (`threads`), episode snapshots (`snapshot`). The registered
envs (`TrackEnv`, `ReachEnv`, `FindEnv`) are subclasses that only fix the task kind and
document it.
"""

from __future__ import annotations

from typing import Any, Mapping, Optional

import gymnasium as gym
import numpy as np

from morphosim_gym.render.api import render as render_scene
from morphosim_gym.rig import AGENT_OBJECT_ID
from morphosim_gym.scene import Scene4D
from morphosim_gym.tasks import Task, TaskView, check_camera_override, describe_object, make_task
from morphosim_gym.tasks.spec import SceneRequest

from .config import RENDER_MODES, EnvConfig, env_signature, make_sim, render_backend_of
from .edits import apply_edit, view_camera_option, view_change
from .options import ResetOptions
from .scene_file import load_fixed_scene
from .scenes import SceneChooser, SceneSource
from .snapshot import EnvSnapshot, restore_snapshot, take_snapshot
from .spaces import Observations, action_space, check_action, observed_cameras
from .threads import numba_threads
from .world import SceneWorld

__all__ = ["MorphoSimEnv"]

Views = dict[str, tuple]          # camera name -> (camera, rgb, depth, instance) of one render


class MorphoSimEnv(gym.Env):
    """Base class of the MorphoSim envs; see `TrackEnv`, `ReachEnv`, `FindEnv` for the documented
    envs. Keyword arguments: the fields of `EnvConfig` (over the class's `config_defaults`)."""

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 10}
    task_kind = ""
    config_defaults: Mapping[str, Any] = {}
    __signature__ = env_signature()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.__signature__ = env_signature(cls.config_defaults)       # what help() and IDEs show

    def __init__(self, _scene_source: Optional[SceneSource] = None, **kwargs: Any) -> None:
        """`_scene_source` (internal, for `MorphoSimVectorEnv`): a `SceneSource` of another env made
        with the same `sim`, shared so that its pool is built once and its scenes (immutable, with
        their pose caches) serve every env of the batch."""
        cfg = self.config = EnvConfig.from_kwargs(kwargs, self.config_defaults)
        task = cfg.task if cfg.task is not None else self.task_kind
        self._task: Task = make_task(task, **dict(cfg.task_params or {}))
        if self._task.kind != self.task_kind:
            raise ValueError(f"Expected a task of kind {self.task_kind!r} for this env, found {self._task.kind!r}")
        self._rig = self._task.make_rig()
        self._sim = make_sim(cfg.sim)
        self._render_backend = render_backend_of(self._sim)
        self._source = _scene_source if _scene_source is not None else SceneSource(self._sim)
        self._fixed = load_fixed_scene(cfg.scene)            # a bad file or target fails here, at make
        if self._fixed is not None:
            self._fixed.resolve_target(self._task, cfg.target)
        cams = observed_cameras(cfg.cameras, self._task.default_cameras, self._rig.camera_names)
        self._observe = Observations(cams, cfg.width, cfg.height, cfg.depth, cfg.segmentation, self._rig)
        self._render_cams = cams + tuple(c for c in (self._task.task_camera,) if c not in cams)
        self._dt = 1.0 / cfg.control_hz
        self._render_agent = self._task.render_agent if cfg.render_agent is None else bool(cfg.render_agent)
        self.render_mode = cfg.render_mode
        self.metadata = dict(self.metadata, render_fps=cfg.control_hz)
        self.observation_space = self._observe.space
        self.action_space = action_space(self._rig)
        self._scenes = SceneChooser(self._task, cfg.prompt, cfg.target, cfg.scene_seed, cfg.scene_pool, cfg.pool_seed)
        self._scenes.prebuild(self._source, cfg.pool_workers, cfg.pool_backend,
                              cfg.pool_timeout_s)            # resets from the pool do not generate
        self._world: Optional[SceneWorld] = None
        self._step_count = 0
        self._edits: list[str] = []
        self._edit_errors: list[str] = []
        self._episode: dict[str, Any] = {}

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
    def render_backend(self) -> str:
        """The renderer of observations and `render()`: the sim's `config.render_backend` ("cpu" default)."""
        return self._render_backend

    @property
    def dt(self) -> float:
        """Seconds of scene time per step (1 / control_hz)."""
        return self._dt

    # ================================================================== reset
    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[dict, dict]:
        super().reset(seed=seed)
        opts = ResetOptions.parse(options)
        with numba_threads(self.config.render_threads):
            return self._reset(opts)

    def _reset(self, opts: ResetOptions) -> tuple[dict, dict]:
        self._reset_begin(opts)
        return self._reset_end(self._render(self.world.t))

    def _reset_begin(self, opts: ResetOptions) -> None:
        """The part of a reset before its render: choose and edit the scene, place the rig."""
        rng = self.np_random
        target_name = opts.target if opts.target is not None else self.config.target
        if self._fixed is not None and opts.prompt is None:
            scene, scene_seed = self._fixed.scene, None
            request = SceneRequest(self._fixed.prompt, target_name or "", "")
            target = self._fixed.resolve_target(self._task, target_name)
        else:
            request, scene_seed = self._scenes.choose(rng, opts)
            scene = self._source.get(request.prompt, scene_seed)
            target = self._task.resolve_target(scene, target_name or request.target or None)
        description = request.target_description if request.target_description and not target_name \
            else describe_object(target, scene)
        policy = opts.on_edit_error or self.config.on_edit_error
        self._edits, self._edit_errors = [], []
        world = SceneWorld(scene, target)          # geometry (target size, focus) from the unedited scene
        unedited = scene
        for text in opts.edits:
            scene = self._edit(scene, text, policy)
        world.set_scene(scene)
        self._world, self._step_count = world, 0
        camera = view_camera_option(unedited, scene, opts.camera, self._task.params.get("fov_y_deg"))
        self._task.initialize_episode(world, self._rig, rng, camera)
        self._episode = {"prompt": request.prompt, "scene_seed": scene_seed, "target": target.name,
                         "target_id": target.id, "instruction": self._task.instruction(description),
                         "edit_policy": policy}

    def _reset_end(self, rendered: tuple[Views, TaskView]) -> tuple[dict, dict]:
        """The part of a reset after its render (`_render`'s views): the first observation and info."""
        views, view = rendered
        metrics = dict(self._task.measure(self.world, self._rig, view), **self._task.reset_metrics())
        return self._observe(views, self._rig.proprio()), self._info(views, False, {}, metrics)

    # ================================================================== edits
    def _edit(self, scene: Scene4D, text: str, policy: str) -> Scene4D:
        new, error = apply_edit(self._sim, scene, text, policy)
        if error is None:
            self._edits.append(text)
        else:
            self._edit_errors.append(error)
        return new

    def perturb(self, text: str) -> bool:
        """Apply a language edit to the scene now; the observation from the next step shows it.

        Returns True if the edit was applied, False if it failed and the env (or the episode's
        reset options) say `on_edit_error="skip"`; otherwise a failed edit raises
        `ms.EditError` / `ms.CommandError` and the scene stays as it was. To schedule edits by
        step or by chance, wrap the env in `LanguagePerturbation`.
        """
        if not isinstance(text, str) or not text.strip():
            raise ValueError(f"Expected an edit command (a non-empty string), found {text!r}")
        world = self.world
        before = world.scene
        new = self._edit(before, text, self._episode.get("edit_policy", self.config.on_edit_error))
        if new is before:
            return False
        view = view_change(before, new)
        if view is not None:                       # a camera edit: the task moves its camera as the edit says
            self._task.change_view(world, self._rig, *view)
        world.set_scene(new)
        return True

    def move_camera(self, camera: Mapping[str, Any]) -> None:
        """Move the task's camera now, mid-episode, as the reset `camera` option would have placed it:
        by the offset from the scene's generation camera to `camera["position"]`, and to the field of
        view `camera["fov_y_deg"]` relative to the generation camera's (keys as the reset option's;
        `look_at` is a reset-only key). The next observation shows it; the scene is untouched."""
        checked = check_camera_override(camera)
        if "look_at" in checked:
            raise ValueError("Expected a mid-episode camera move without 'look_at' (a reset-only key), found it")
        if not checked:
            raise ValueError(f"Expected a camera move with 'position' and/or 'fov_y_deg', found {camera!r}")
        generation = self.world.scene.camera
        ratio = checked.get("fov_y_deg", generation.fov_y_deg) / generation.fov_y_deg
        shift = checked.get("position", np.asarray(generation.position, dtype=np.float64)) - np.asarray(
            generation.position, dtype=np.float64)
        self._task.change_view(self.world, self._rig, float(ratio), shift)

    # ================================================================== branching
    def snapshot(self) -> EnvSnapshot:
        """The episode's state now, as an opaque, picklable `EnvSnapshot`: the world (the scene is
        shared, not copied), the rig, the task's counters, the step count, the edit log and the
        numpy RNG. `restore(snapshot)` returns to it, as often as wanted, to branch an episode.
        Wrappers' own state (e.g. `LanguagePerturbation`'s schedule) is not included; to clone a
        whole wrapped env use `copy.deepcopy(env)` or `pickle`."""
        return take_snapshot(self)

    def restore(self, snapshot: EnvSnapshot) -> None:
        """Return to a `snapshot()` of this env (or of an env of the same class and arguments); the
        next `step` continues exactly as it did after the snapshot was taken."""
        restore_snapshot(self, snapshot)

    # ================================================================== step
    def step(self, action: Any) -> tuple[dict, float, bool, bool, dict]:
        a = check_action(action, self.action_space.shape)
        with numba_threads(self.config.render_threads):
            return self._step(a)

    def _step(self, a: np.ndarray) -> tuple[dict, float, bool, bool, dict]:
        self._advance(a)
        return self._step_outcome(a, self._render(self.world.t))

    def _advance(self, a: np.ndarray) -> None:
        """The part of a step before its render: move the rig, advance the scene clock."""
        world = self.world
        self._rig.apply(a, self._dt)
        self._step_count += 1
        world.t = min(self._step_count * self._dt, world.duration)

    def _step_outcome(self, a: np.ndarray, rendered: tuple[Views, TaskView]) -> tuple[dict, float, bool, bool, dict]:
        """The part of a step after its render (`_render`'s views): reward, flags, observation, info."""
        world = self.world
        views, view = rendered
        ev = self._task.evaluate(world, self._rig, view, a)
        terminated = bool(self.config.terminate_on_success and ev.terminate)
        truncated = bool(world.t >= world.duration - 1e-9)
        info = self._info(views, ev.success, ev.terms, ev.metrics)
        return self._observe(views, self._rig.proprio()), float(ev.reward), terminated, truncated, info

    # ================================================================== render
    def _sources(self, t: float) -> list:
        g = [self._world.gaussians(t)]
        if self._render_agent:
            g.append(self._rig.gaussians())
        return g

    def _render(self, t: float) -> tuple[Views, TaskView]:
        """Every render camera's view at scene time t, and the task camera's `TaskView`."""
        sources, cams, background, sky = self._render_request(t)
        out = render_scene(sources, cams, background=background, sky=sky, backend=self._render_backend,
                           lod=self.config.render_lod)
        return self._rendered(cams, out, t)

    def _render_request(self, t: float) -> tuple[list, list, tuple, Optional[np.ndarray]]:
        """What `_render` draws at time t: (Gaussian sources, one camera per render camera, background,
        the scene's sky or None)."""
        w, h = self.config.width, self.config.height
        scene = self._world.scene
        return self._sources(t), [self._rig.camera(n, w, h) for n in self._render_cams], scene.background, scene.sky

    def _rendered(self, cams: list, out: Any, t: float) -> tuple[Views, TaskView]:
        """`_render`'s result from the render of its request (`out.rgb[i]` etc. per camera i)."""
        views = {name: (cams[i], out.rgb[i], out.depth[i], out.instance[i]) for i, name in enumerate(self._render_cams)}
        cam, _, _, instance = views[self._task.task_camera]
        return views, TaskView(cam, instance, t)

    def render(self) -> Optional[np.ndarray]:
        """An RGB frame [render_height, render_width, 3] uint8 of the first observation camera
        (with render_mode="rgb_array"; None otherwise)."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to gym.make")
            return None
        cam = self._rig.camera(self._observe.cameras[0], self.config.render_width, self.config.render_height)
        with numba_threads(self.config.render_threads):
            out = render_scene(self._sources(self.world.t), cam, background=self.world.scene.background,
                               sky=self.world.scene.sky, backend=self._render_backend,
                               lod=self.config.render_lod)
        return out.rgb_uint8()

    # ================================================================== info
    def _info(self, views: Views, success: bool, terms: Mapping[str, float], metrics: Mapping[str, Any]) -> dict:
        world = self.world
        cams = {name: {"K": c.K, "world_to_camera": np.array(c.world_to_camera), "width": c.width, "height": c.height}
                for name, (c, _, _, _) in views.items()}
        id_to_name = dict(world.scene.id_to_name)
        if self._render_agent:
            id_to_name[AGENT_OBJECT_ID] = "agent"
        ep = self._episode
        info = {"success": bool(success), "target": ep["target"], "target_id": ep["target_id"],
                "target_position": world.target_position(), "instruction": ep["instruction"], "prompt": ep["prompt"],
                "scene_seed": ep["scene_seed"], "scene_id": world.scene.content_hash(), "edits": tuple(self._edits),
                "edit_errors": tuple(self._edit_errors), "t": float(world.t), "step": self._step_count,
                "cameras": cams, "id_to_name": id_to_name}
        info.update({k: float(v) for k, v in terms.items()})
        info.update(metrics)
        return info

    def close(self) -> None:
        self._world = None
        super().close()
