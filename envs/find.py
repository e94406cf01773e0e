"""MorphoSim/Find-v0: a free-flying camera finds and centres the object the instruction names."""

from __future__ import annotations

from .core import MorphoSimEnv

__all__ = ["FindEnv"]


class FindEnv(MorphoSimEnv):
    """
    ## Description

    A scene with the target and two or three distractors ("a red ball moves slowly from left
    to right next to a blue ball, a green cube and a yellow mug on a table") and the
    instruction "find the red ball": a free-flying camera (MuJoCo free joint,
    `morphosim_gym/rig/free_camera.xml`) starts turned away from the scene and must bring
    the named object to the centre of its view, large enough. Distractors may share the
    target's category or its colour, never both, so the instruction must be grounded.
    Scenes come from `tasks/find.yaml` or from `prompt`.

    ## Action Space

    `Box(-1, 1, (6,), float32)`, in the camera body's frame; outside [-1, 1] clipped,
    non-finite values rejected with a `ValueError` (the step is not taken).

    | Num | Action           | Min | Max | Unit at +-1                                     |
    |-----|------------------|-----|-----|-------------------------------------------------|
    | 0   | velocity right   | -1  | 1   | 0.5 generation-camera distances per second      |
    | 1   | velocity forward | -1  | 1   | same                                            |
    | 2   | velocity up      | -1  | 1   | same                                            |
    | 3   | yaw rate         | -1  | 1   | 60 deg/s, positive turns left                   |
    | 4   | pitch rate       | -1  | 1   | 60 deg/s, positive looks up                     |
    | 5   | roll rate        | -1  | 1   | 60 deg/s                                        |

    The position stays in a box of +-2 generation distances around the scene's focus,
    from just above the ground to 1.5 generation distances above the focus.

    ## Observation Space

    `Dict`:
    - `rgb`: `Box(0, 255, (height, width, 3), uint8)`, the free camera's image (60 deg).
    - `depth`, `segmentation` (optional): as in Track.
    - `proprio`: `Box(low, high, (15,), float32)`: position relative to the focus divided by
      the generation distance [3] (clipped to +-10), the body's x and y axes in the world
      [6], the last action [6].

    ## Rewards

    `reward = reward_facing + reward_centred + reward_size + reward_ctrl`, in [-0.02, 1]:
    - `reward_facing = 0.2 * tolerance(angle, (0, 10 deg), margin=90 deg)`, angle between the
      camera axis and the direction to the target;
    - `reward_centred = 0.5 * visible * tolerance(d, (0, 0.2), margin=1)`, `d` the distance
      of the target's visible pixels' centroid from the image centre (half-image units);
    - `reward_size = 0.3 * visible * tolerance(area, (0.01, 1), margin=0.01)`, `area` the
      fraction of the image the target covers;
    - `reward_ctrl = -0.02 * mean(action ** 2)`.

    ## Starting State

    On a ring around the scene's focus at 0.9-1.2 generation distances, at the generation
    camera's height, random azimuth, turned 45-150 deg away from the focus (either side).

    ## Episode End

    Success (`info["success"]`): the target visible, centred (`d <= 0.2`) and covering at
    least 1% of the image for 2 consecutive steps. With `terminate_on_success=True`
    (default) the episode terminates then; it truncates at the end of the clip (6 s; 60
    steps at 10 Hz).

    ## Arguments

    | Parameter | Type | Default | Description |
    |---|---|---|---|
    | `task` | `str \\| TaskSpec \\| dict \\| None` | `None` | task spec: a built-in name, a YAML path, a mapping; None = `"find"` |
    | `prompt` | `str \\| None` | `None` | fixed prompt for every episode instead of the task's scene distribution |
    | `target` | `str \\| None` | `None` | target object name; None = the first moving object (else the first object) |
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
    | `render_agent` | `bool \\| None` | `None` | draw the camera body; None = task default (False) |
    | `terminate_on_success` | `bool` | `True` | terminate when the target has been found |
    | `on_edit_error` | `str` | `"raise"` | failed edits: `"raise"`, or `"skip"` and go on with the unedited scene |
    | `render_mode` | `str \\| None` | `None` | `"rgb_array"` for `render()` |
    | `render_width` | `int` | `256` | `render()` frame width |
    | `render_height` | `int` | `256` | `render()` frame height |
    | `render_threads` | `int \\| None` | `1` | numba threads for this env's skinning and rendering (set per call, then restored); None = numba's default |
    | `render_lod` | `bool` | `False` | draw far object blocks as cached coarser merged Gaussians (`render.lod`, an approximation: off = exact images); CPU backend only |
    | `sim` | `MorphoSim \\| SimConfig \\| None` | `None` | the world: a `MorphoSim` or a `SimConfig`; None = `envs.config.DEFAULT_SIM_CONFIG` (oracle, detail 0.35) |
    | `task_params` | `dict \\| None` | `None` | overrides of `FindTask.PARAMS` |

    Reset options: `prompt`, `scene_seed`, `target`, `edits`, `camera` (`position`,
    `look_at`, `fov_y_deg` of the free camera's start), `on_edit_error`.

    ## Version History

    - v0: initial version.
    """

    task_kind = "find"
    config_defaults = {"terminate_on_success": True}
