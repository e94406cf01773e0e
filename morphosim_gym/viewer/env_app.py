"""`EnvViewer`: watch an env's episodes in the browser (`morphosim view --env MorphoSim/Track-v0`).

The page shows, live while a policy acts:
  * the observation (what the agent sees) in the side panel, and as an image on the agent
    camera's frustum in the scene;
  * a third-person view: the world and the agent's own Gaussians rendered by our renderer from
    the page's orbit camera (falls back to `env.render()` for envs without a MorphoSim world);
  * step, reward (and its terms), return, success, the instruction and the target;
  * play / pause, one step, a new episode, steps per second, and a box for language edits applied
    to the running episode (`env.unwrapped.perturb`, where the env has it).

Policies follow the one protocol of `morphosim_gym.policies` (as in `morphosim bench`): a factory
`factory(env, seed) -> act(obs, info) -> action`, called once per episode with its reset seed, named
by anything `resolve_policy` takes: a built-in ("random", the default, "zero", "oracle", "color"),
"module:callable", or the factory itself.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from ..policies import Act, PolicyFactory, policy_for_episode, resolve_policy
from ..scene import Camera, Gaussians
from .camera import camera_from_viewer, render_size, viewer_pose, viewer_view
from .session import DEFAULT_MAX_LOG, md_escape
from .lifecycle import ServedViewer
from .worker import FrameWorker

__all__ = ["EnvViewer", "EnvRunner", "StepRecord"]


@dataclass(frozen=True)
class StepRecord:
    """What one reset or step gave.

    Attributes:
        episode: episode number (from 1).
        step: steps taken in the episode (0 after reset).
        obs: the observation.
        reward: this step's reward (0 after reset); episode_return: the sum so far.
        terminated, truncated: as Gymnasium returns them.
        info: the step's info dict.
        version: grows with every reset, step and edit.
    """

    episode: int
    step: int
    obs: Any
    reward: float
    episode_return: float
    terminated: bool
    truncated: bool
    info: dict
    version: int

    @property
    def done(self) -> bool:
        return self.terminated or self.truncated

    @property
    def success(self) -> Optional[bool]:
        s = self.info.get("success")
        return None if s is None else bool(s)


class EnvRunner:
    """Runs episodes of an env with a policy, one step at a time, thread-safely (the web layer
    steps it from a timer thread and reads it from render threads).

    Args:
        env: a Gymnasium env, or an env id for `gym.make` (with `render_mode="rgb_array"`).
        policy: a policy spec or factory (see `morphosim_gym.policies.resolve_policy`); its factory is
            called after every reset with the env and that reset's seed.
        seed: seed of the first reset (episode k is reset with seed + k - 1).
        env_kwargs: keyword arguments for `gym.make`.
    """

    def __init__(self, env: Any, policy: str | PolicyFactory = "random", seed: int = 0,
                 env_kwargs: Optional[dict] = None) -> None:
        import gymnasium as gym

        import morphosim_gym.envs  # noqa: F401  (registers the MorphoSim envs)

        self.factory = resolve_policy(policy)       # before making the env: a bad spec fails at once
        if isinstance(env, str):
            if env not in gym.registry:
                known = sorted(k for k in gym.registry if k.startswith("MorphoSim/"))
                raise ValueError(f"Expected a registered env id, found {env!r}; MorphoSim envs: {known}")
            env = gym.make(env, render_mode="rgb_array", **dict(env_kwargs or {}))
        self.env = env
        self.env_id = getattr(getattr(env, "spec", None), "id", None) or type(env.unwrapped).__name__
        self.act: Optional[Act] = None
        self.seed = int(seed)
        self.lock = threading.RLock()
        self.episode = 0
        self.record: Optional[StepRecord] = None
        self.rewards: list[float] = []
        self.edit_log: deque[tuple[str, bool, str]] = deque(maxlen=DEFAULT_MAX_LOG)   # the newest edits
        self._version = 0
        self.reset()

    # ------------------------------------------------------------- episodes
    def reset(self) -> StepRecord:
        """Start the next episode."""
        with self.lock:
            self.episode += 1
            seed = self.seed + self.episode - 1
            obs, info = self.env.reset(seed=seed)
            self.act = policy_for_episode(self.factory, self.env, seed)
            self.rewards = []
            return self._set(StepRecord(self.episode, 0, obs, 0.0, 0.0, False, False, dict(info), 0))

    def step(self) -> StepRecord:
        """One step with the policy; a finished episode is followed by a reset."""
        with self.lock:
            if self.record is not None and self.record.done:
                return self.reset()
            rec = self.record
            action = self.act(rec.obs, rec.info)
            obs, reward, terminated, truncated, info = self.env.step(action)
            self.rewards.append(float(reward))
            return self._set(StepRecord(rec.episode, rec.step + 1, obs, float(reward),
                                        rec.episode_return + float(reward), bool(terminated), bool(truncated),
                                        dict(info), 0))

    def perturb(self, text: str) -> tuple[bool, str]:
        """Apply a language edit to the running episode (envs with `perturb`); (applied, message)."""
        text = str(text).strip()
        fn = getattr(self.env.unwrapped, "perturb", None)
        if not text:
            return False, "Expected an edit command, found empty text"
        if fn is None:
            return False, f"{self.env_id} does not take language edits during an episode"
        with self.lock:
            try:
                applied = bool(fn(text))
            except ValueError as exc:
                self.edit_log.append((text, False, str(exc)))
                return False, str(exc)
            msg = "applied" if applied else "skipped (the env's on_edit_error is 'skip')"
            self.edit_log.append((text, applied, msg))
            self._version += 1
            return applied, msg

    def _set(self, rec: StepRecord) -> StepRecord:
        self._version += 1
        rec = StepRecord(**{**rec.__dict__, "version": self._version})
        self.record = rec
        return rec

    @property
    def version(self) -> int:
        return self._version

    # ------------------------------------------------------------- images
    @property
    def observation_image(self) -> Optional[np.ndarray]:
        """[H, W, 3] uint8 of the observation (its "rgb" entry, or the observation itself if it is an image)."""
        obs = self.record.obs if self.record else None
        img = obs.get("rgb") if isinstance(obs, dict) else obs
        if isinstance(img, np.ndarray) and img.ndim == 3 and img.shape[-1] == 3:
            return img.astype(np.uint8, copy=False)
        return None

    @property
    def has_world(self) -> bool:
        """Whether the env exposes a MorphoSim world (third-person views from any camera)."""
        u = self.env.unwrapped
        return hasattr(u, "world") and hasattr(u, "rig")

    def world_gaussians(self) -> tuple[Gaussians, tuple[float, float, float]]:
        """A copy of the world's and the agent's Gaussians now, and the background colour."""
        u = self.env.unwrapped
        with self.lock:
            world = u.world
            parts = [world.gaussians()]
            agent = getattr(u.rig, "gaussians", None)
            if agent is not None:
                parts.append(agent())
            g = Gaussians.concat(parts).numpy()        # a copy: the env may step while we render
            return g, tuple(world.scene.background)

    def default_camera(self, width: int, height: int) -> Camera:
        """A third-person camera: the scene's generation camera, pulled back and raised to show the agent."""
        u = self.env.unwrapped
        with self.lock:
            if self.has_world:
                cam = u.world.scene.camera
                centre = self.orbit_centre()
                back = cam.position - centre
                eye = centre + 2.0 * back + np.array([0.0, 0.0, 0.6 * np.linalg.norm(back)])
                return Camera.look_at(eye, centre, width, height, fov_y_deg=cam.fov_y_deg)
        return Camera.look_at((0, -4, 2), (0, 0, 0.5), width, height, 50)

    def orbit_centre(self) -> np.ndarray:
        """[3] what the third-person camera orbits: the scene centre."""
        if self.has_world:
            return self.env.unwrapped.world.scene.centre()
        return np.array([0.0, 0.0, 0.5])

    def agent_cameras(self) -> dict[str, Camera]:
        """The env's cameras at the last step (from `info["cameras"]`), by name."""
        out = {}
        for name, c in (self.record.info.get("cameras") or {}).items() if self.record else ():
            try:
                K = np.asarray(c["K"], dtype=np.float64)
                out[name] = Camera(int(c["width"]), int(c["height"]), K[0, 0], K[1, 1], K[0, 2], K[1, 2],
                                   np.asarray(c["world_to_camera"], dtype=np.float64))
            except (KeyError, TypeError, ValueError):
                continue
        return out

    def close(self) -> None:
        self.env.close()


def _fmt(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (float, np.floating)):
        return f"{float(v):.3f}"
    return md_escape(str(v))


class EnvViewer(ServedViewer):
    """Serve an env's episodes in the browser.

    Args:
        env: an env id (or a Gymnasium env).
        policy: a built-in ("random", the default, "zero", "oracle", "color"), "module:callable" or a
            factory (see `EnvRunner`).
        seed: seed of the first episode.
        episodes: stop playing after this many episodes (0: keep going).
        env_kwargs: keyword arguments for `gym.make`.
        host, port, long_side, jpeg_quality, verbose: as `SceneViewer`.
        steps_per_second: playback speed (default the env's `render_fps`, else 10).
        autoplay: start playing at once.
    """

    def __init__(self, env: Any, policy: str | PolicyFactory = "random", *, seed: int = 0, episodes: int = 0,
                 env_kwargs: Optional[dict] = None, host: str = "127.0.0.1", port: int = 8080, long_side: int = 512,
                 jpeg_quality: int = 85, steps_per_second: Optional[float] = None, autoplay: bool = True,
                 verbose: bool = True) -> None:
        from .app import import_viser

        viser = import_viser()
        self.runner = EnvRunner(env, policy, seed, env_kwargs)
        fps = steps_per_second or float(self.runner.env.metadata.get("render_fps") or 10.0)
        self.long_side = int(long_side)
        self.jpeg_quality = int(jpeg_quality)
        self.max_episodes = int(episodes)
        self.frames: dict[int, dict] = {}
        super().__init__()
        self._serve(viser, host, port, verbose)
        self.server.scene.set_up_direction("+z")
        self.server.scene.world_axes.visible = False
        self._frames = FrameWorker(name="morphosim-env-frames")
        self._scene_id = self.runner.record.info.get("scene_id")
        self._build_gui(fps, autoplay)
        self._set_initial_camera()
        self.server.on_client_connect(self._on_connect)
        self.server.on_client_disconnect(lambda c: (self._frames.discard(c.client_id),
                                                    self.frames.pop(c.client_id, None)))
        self._show(self.runner.record)
        self._loop = threading.Thread(target=self._play_loop, name="morphosim-env-play", daemon=True)
        self._loop.start()

    # ================================================================ lifecycle
    def close(self) -> None:
        if self._closed.is_set():
            return
        self._closed.set()
        self._loop.join(timeout=5.0)
        self._frames.stop()
        self.server.stop()
        self.runner.close()

    def wait_idle(self, timeout: float = 10.0) -> bool:
        return self._frames.wait_idle(timeout)

    @property
    def panel_text(self) -> str:
        """What the episode panel shows (markdown)."""
        return "\n".join(m.content for m in (self._title, self._stats, self._edit_status))

    # ================================================================ GUI
    def _build_gui(self, fps: float, autoplay: bool) -> None:
        gui = self.server.gui
        gui.configure_theme(control_width="large", show_logo=False, show_share_button=False)
        self._title = gui.add_markdown("")
        with gui.add_folder("Observation"):
            obs = self.runner.observation_image
            self._obs_image = gui.add_image(obs if obs is not None else np.zeros((8, 8, 3), np.uint8),
                                            label="what the agent sees", format="png")
        with gui.add_folder("Episode"):
            self._stats = gui.add_markdown("")
            self._play = gui.add_checkbox("Play", bool(autoplay))
            self._speed = gui.add_slider("Steps per second", min=0.5, max=30.0, step=0.5,
                                         initial_value=float(min(max(fps, 0.5), 30.0)))
            self._buttons = gui.add_button_group("Control", ("Step", "New episode"))
            self._show_frustums = gui.add_checkbox("Agent camera in view", True)
        with gui.add_folder("Edit the world", expand_by_default=False):
            self._edit_box = gui.add_text("Edit", "", multiline=True,
                                          hint="A language edit applied to the running episode, e.g. "
                                               "'make the ball blue'; Enter applies it.")
            self._edit_status = gui.add_markdown("")
        self._buttons.on_click(self._on_button)
        self._edit_box.on_update(self._on_edit_text)
        self._show_frustums.on_update(lambda _: self._update_frustums())

    def _on_button(self, event: Any) -> None:
        if event.target.value == "New episode":
            rec = self.runner.reset()
        else:
            rec = self.runner.step()
        self._show(rec)

    def _on_edit_text(self, event: Any) -> None:
        value = self._edit_box.value
        if "\n" not in value:
            return
        text = " ".join(line.strip() for line in value.splitlines() if line.strip())
        ok, msg = self.runner.perturb(text)
        self._edit_box.value = "" if ok else text
        self._edit_status.content = (f"**Done**: {md_escape(text)} - {md_escape(msg)}" if ok
                                     else f"**Error**: {md_escape(text)}: {md_escape(msg)}")
        self._request_all()

    def _stats_text(self, rec: StepRecord) -> str:
        info = rec.info
        lines = [f"**Episode {rec.episode}**, step {rec.step}"
                 + (" (terminated)" if rec.terminated else " (truncated)" if rec.truncated else ""),
                 f"- reward: {rec.reward:.3f}, return: {rec.episode_return:.3f}",
                 f"- success: {_fmt(rec.success) if rec.success is not None else 'n/a'}"]
        terms = {k: v for k, v in info.items() if k.startswith("reward_")}
        if terms:
            lines.append("- terms: " + ", ".join(f"{md_escape(k)} {_fmt(v)}" for k, v in terms.items()))
        for key in ("t", "target"):
            if key in info:
                lines.append(f"- {key}: {_fmt(info[key])}")
        return "\n".join(lines)

    def _show(self, rec: StepRecord) -> None:
        info = rec.info
        if rec.step == 0 and info.get("scene_id") != self._scene_id:     # a new episode in another scene
            self._scene_id = info.get("scene_id")
            self._set_initial_camera()
            for client in self.server.get_clients().values():
                self._reset_camera(client)
        title = f"**MorphoSim** — {md_escape(self.runner.env_id)}"
        if info.get("instruction"):
            title += f"  \n*{md_escape(info['instruction'])}*"
        if info.get("prompt"):
            title += f"  \nscene: {md_escape(info['prompt'])}"
        self._title.content = title
        self._stats.content = self._stats_text(rec)
        obs = self.runner.observation_image
        if obs is not None:
            scale = max(1, 256 // max(obs.shape[:2]))
            self._obs_image.image = np.repeat(np.repeat(obs, scale, 0), scale, 1)
        self._update_frustums()
        self._request_all()

    def _update_frustums(self) -> None:
        cams = self.runner.agent_cameras() if self._show_frustums.value else {}
        obs = self.runner.observation_image
        centre = self.runner.orbit_centre()
        for i, (name, cam) in enumerate(cams.items()):
            wxyz, pos = viewer_pose(cam)
            size = 0.12 * float(np.linalg.norm(pos - centre))      # in proportion to the scene
            self.server.scene.add_camera_frustum(
                f"/agent/{name}", fov=math.radians(cam.fov_y_deg), aspect=cam.width / cam.height, scale=size,
                thickness=2.0, thickness_units="screen", color=(255, 140, 0), image=obs if i == 0 else None,
                format="jpeg", wxyz=wxyz, position=pos)
        if not cams:
            self.server.scene.remove_by_name("/agent")

    # ================================================================ frames
    def _on_connect(self, client: Any) -> None:
        client.camera.on_update(lambda _: self._request(client.client_id))
        self._request(client.client_id)

    def _request_all(self) -> None:
        for cid in list(self.server.get_clients()):
            self._request(cid)

    def _request(self, client_id: int) -> None:
        if not self._closed.is_set():
            self._frames.request(client_id, lambda: self._send_frame(client_id))

    def _client_camera(self, client: Any) -> Camera:
        cam = client.camera
        try:
            wxyz, position, fov, aspect = cam.wxyz, cam.position, cam.fov, cam.aspect
        except (AssertionError, ZeroDivisionError):
            w, h = render_size(16 / 9, self.long_side)
            return self.runner.default_camera(w, h)
        w, h = render_size(aspect if math.isfinite(aspect) and aspect > 0 else 16 / 9, self.long_side)
        return camera_from_viewer(wxyz, position, fov, w, h)

    def _send_frame(self, client_id: int) -> None:
        from ..render import render

        client = self.server.get_clients().get(client_id)
        if client is None:
            return
        version = self.runner.version
        if self.runner.has_world:
            camera = self._client_camera(client)
            g, bg = self.runner.world_gaussians()
            image = render(g, camera, background=bg).rgb_uint8()
        else:
            camera = None
            with self.runner.lock:
                image = self.runner.env.render()
            if image is None:
                return
        client.scene.set_background_image(image, format="jpeg", jpeg_quality=self.jpeg_quality)
        client.flush()
        self.frames[client_id] = {"version": version, "image": image, "camera": camera}

    # ================================================================ cameras
    def _set_initial_camera(self) -> None:
        cam = self.runner.default_camera(160, 90)
        view = viewer_view(cam, self.runner.orbit_centre())
        init = self.server.initial_camera
        init.position = tuple(view["position"])
        init.look_at = tuple(view["look_at"])
        init.up = tuple(view["up_direction"])
        init.fov = view["fov"]

    def _reset_camera(self, client: Any) -> None:
        view = viewer_view(self.runner.default_camera(160, 90), self.runner.orbit_centre())
        try:
            with client.atomic():
                client.camera.up_direction = tuple(view["up_direction"])
                client.camera.position = tuple(view["position"])
                client.camera.look_at = tuple(view["look_at"])
                client.camera.fov = view["fov"]
        except AssertionError:          # no camera report from the page yet: it starts at the initial view
            pass

    # ================================================================ playback
    def _play_loop(self) -> None:
        next_at = time.perf_counter()
        while not self._closed.is_set():
            period = 1.0 / max(float(self._speed.value), 0.1)
            now = time.perf_counter()
            if now < next_at:
                self._closed.wait(min(next_at - now, 0.1))
                continue
            next_at = now + period
            if not self._play.value:
                continue
            rec = self.runner.record
            if rec is not None and rec.done and self.max_episodes and rec.episode >= self.max_episodes:
                self._play.value = False
                continue
            self._show(self.runner.step())
