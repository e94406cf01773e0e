"""MorphoSim/Track-v0: keep a named moving object centred with a pan-tilt camera."""

from __future__ import annotations

from .core import MorphoSimEnv

__all__ = ["TrackEnv"]


class TrackEnv(MorphoSimEnv):
    """
    ## Description

    A sentence ("a red ball bounces from right to left") becomes a dynamic 3D Gaussian scene
    (MorphoSim). A pan-tilt camera on a tripod stands where the scene's generation camera
    was, narrower in view, and must keep the named moving object in the centre of its
    image while the object moves; the object leaves the view if the camera does not
    follow. The instruction ("keep the red ball in the centre of the view") and the target
    are in `info`. Scenes come from the task's scene distribution (`tasks/track.yaml`: ten
    object categories from balls to horses, eight colours, straight, bouncing, circling,
    zigzag and back-and-forth motions at three speeds), or from `prompt`.

    ## Action Space

    `Box(-1, 1, (3,), float32)`; values outside [-1, 1] are clipped, non-finite values are
    rejected with a `ValueError` (the step is not taken).

    | Num | Action    | Min | Max | Unit at +-1                                 |
    |-----|-----------|-----|-----|---------------------------------------------|
    | 0   | pan rate  | -1  | 1   | 60 deg/s, positive turns left               |
    | 1   | tilt rate | -1  | 1   | 45 deg/s, positive looks up                 |
    | 2   | zoom rate | -1  | 1   | 20 deg/s of field of view, positive zooms in |

    Pan is limited to +-100 deg, tilt to +-60 deg, the field of view to [12, 50] deg.

    ## Observation Space

    `Dict`:
    - `rgb`: `Box(0, 255, (height, width, 3), uint8)`, the pan-tilt camera's image.
    - `depth` (with `depth=True`): `Box(0, inf, (height, width), float32)`, metres along the
      camera axis (0 where nothing is drawn).
    - `segmentation` (with `segmentation=True`): `Box(-1, 100, (height, width), int32)`,
      object ids (`info["id_to_name"]`), -1 background.
    - `proprio`: `Box(low, high, (6,), float32)`: pan (rad, +-1.745), tilt (rad, +-1.047), zoom in [-1, 1]
      (-1 widest), the last applied action [3].

    With several `cameras`, the first gives `rgb`/`depth`/`segmentation` and each other
    camera `name` adds `rgb_name` (and `depth_name`, `segmentation_name`).

    ## Rewards

    `reward = reward_centred + reward_framing + reward_ctrl`, in [-0.02, 1]:
    - `reward_centred = 0.8 * c`, with `c = tolerance(d, (0, 0.15), margin=0.5, sigmoid="long_tail")`
      (1 inside the radius, 0.55 at twice it, a dense signal across the image) and `d` the
      distance of the target's projected centre from the image centre in half-image units;
    - `reward_framing = 0.2 * c * tolerance(size, (0.12, 0.6), margin=0.15)`, with `size` the
      target's apparent diameter as a fraction of the image height;
    - `reward_ctrl = -0.02 * mean(action ** 2)`.

    The terms are in `info` under the same names. Weights and radii are task parameters
    (`tasks/track.yaml` `params`, or `task_params`).

    ## Starting State

    The camera is aimed at the target's start position plus a uniform random pan and tilt
    error of up to 0.6 half-fields of view each, at a 30 deg field of view. Scene time 0.

    ## Episode End

    The episode truncates when scene time reaches the end of the clip (49 frames at 8 fps =
    6 s; 60 steps at the default 10 Hz). It never terminates. `info["success"]` is True when
    the target was centred (`d <= 0.15` and visible) on at least 70% of the steps so far.

    ## Arguments

    | Parameter | Type | Default | Description |
    |---|---|---|---|
    | `task` | `str \\| TaskSpec \\| dict \\| None` | `None` | task spec: a built-in name, a YAML path, a mapping; None = `"track"` |
    | `prompt` | `str \\| None` | `None` | fixed prompt for every episode instead of the task's scene distribution |
    | `target` | `str \\| None` | `None` | target object name; None = the first moving object of the prompt |
    | `scene` | `str \\| os.PathLike \\| Scene4D \\| None` | `None` | one fixed world for every episode: a scene file (`DIR/scene.msim` from `morphosim reconstruct VIDEO --out DIR`) or a `Scene4D`; not with `prompt` or `scene_pool`; a file that is not a scene or a `target` not in it fails at `make` |
    | `scene_seed` | `int \\| None` | `None` | fixed generation seed; None = drawn from the reset seed |
    | `scene_pool` | `int \\| None` | `None` | pre-build this many scenes at construction; resets draw from them |
    | `pool_seed` | `int` | `0` | seed of the scene pool's draws |
    | `pool_workers` | `int \\| None` | `1` | processes that build the scene pool at construction (1: here; None: one per CPU) |
    | `pool_backend` | `str` | `"process"` | how the pool is built in parallel: `"process"` (local process pool) or `"ray"` |
    | `pool_timeout_s` | `float \\| None` | `None` | seconds one pooled scene may take to build; None = `envs.pool.DEFAULT_SCENE_TIMEOUT_S` (3600) |
    | `width` | `int` | `84` | observation image width, pixels |
    | `height` | `int` | `84` | observation image height, pixels |
    | `depth` | `bool` | `False` | add `depth` observations |
    | `segmentation` | `bool` | `False` | add `segmentation` (instance id) observations |
    | `cameras` | `tuple[str, ...] \\| None` | `None` | rig cameras to observe; None = `("eye",)` |
    | `control_hz` | `float` | `10.0` | control rate; scene time advances 1 / control_hz per step |
    | `render_agent` | `bool \\| None` | `None` | draw the rig's own geoms; None = task default (False) |
    | `terminate_on_success` | `bool` | `False` | no effect: Track never terminates, the clip's end truncates |
    | `on_edit_error` | `str` | `"raise"` | failed edits: `"raise"`, or `"skip"` and go on with the unedited scene |
    | `render_mode` | `str \\| None` | `None` | `"rgb_array"` for `render()` |
    | `render_width` | `int` | `256` | `render()` frame width |
    | `render_height` | `int` | `256` | `render()` frame height |
    | `render_threads` | `int \\| None` | `1` | numba threads for this env's skinning and rendering (set per call, then restored); None = numba's default |
    | `render_lod` | `bool` | `False` | draw far object blocks as cached coarser merged Gaussians (`render.lod`, an approximation: off = exact images); CPU backend only |
    | `sim` | `MorphoSim \\| SimConfig \\| None` | `None` | the world: a `MorphoSim` or a `SimConfig`; None = `envs.config.DEFAULT_SIM_CONFIG` (oracle, detail 0.35) |
    | `task_params` | `dict \\| None` | `None` | overrides of `TrackTask.PARAMS` |

    Reset options: `prompt`, `scene_seed`, `target`, `edits` (language edits applied
    before the episode), `camera` (`position`, `look_at`, `fov_y_deg` of the tripod camera),
    `on_edit_error`. `env.unwrapped.perturb(text)` edits the scene mid-episode; a camera edit
    ("widen the field of view", "raise the camera by 0.5 metres") moves the tripod with the scene's
    camera (pan and tilt kept) and scales the zoom from the next observation on;
    `env.unwrapped.move_camera(camera)` moves it as the reset `camera` option would.

    Branching an episode: `snap = env.unwrapped.snapshot()` saves the episode's state (world,
    rig, task counters, edit log, numpy RNG; the immutable scene is shared, not copied, so it
    costs well under a millisecond) and `env.unwrapped.restore(snap)` returns to it, as often
    as wanted. Each branch continues exactly (observations, rewards, infos) like a fresh run of
    the same actions and edits from step 0::

        snap = env.unwrapped.snapshot()
        env.unwrapped.perturb("make the ball blue")       # branch A: the counterfactual
        a = [env.step(act) for act in actions]
        env.unwrapped.restore(snap)                       # branch B: as it was
        b = [env.step(act) for act in actions]

    Snapshots pickle; whole envs (raw or from `gym.make`) `pickle` and `copy.deepcopy` too,
    mid-episode, and the copy continues like the original.

    ## Version History

    - v0: initial version.
    """

    task_kind = "track"
