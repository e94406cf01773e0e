"""MorphoSim/Reach-v0: bring a 6-DoF arm's end-effector to a moving object (interception)."""

from __future__ import annotations

from .core import MorphoSimEnv

__all__ = ["ReachEnv"]


class ReachEnv(MorphoSimEnv):
    """
    ## Description

    A kinematic 6-DoF arm (MuJoCo, `morphosim_gym/rig/arm6.xml`) stands on the table of a
    generated tabletop scene ("a red cube moves from left to right on a table") and must
    touch the moving object with its gripper (interception). The arm is drawn into the
    render as Gaussians, so the third-person camera sees it with the scene. The arm is
    scaled to the scene: its base stands behind the object's path and its reach is 1.3x
    the farthest point of the path from the shoulder, so the whole path is reachable (see
    `morphosim_gym.tasks.reach`). Scenes come from `tasks/reach.yaml` (eight tabletop
    categories, eight colours, six motions at three speeds) or from `prompt`.

    ## Action Space

    `Box(-1, 1, (6,), float32)`: joint velocities, 90 deg/s at +-1; outside [-1, 1] clipped,
    non-finite values rejected with a `ValueError` (the step is not taken).

    | Num | Joint        | Min | Max | Range (rad)   |
    |-----|--------------|-----|-----|---------------|
    | 0   | base yaw     | -1  | 1   | [-2.97, 2.97] |
    | 1   | shoulder     | -1  | 1   | [-2.0, 2.0]   |
    | 2   | elbow        | -1  | 1   | [-2.6, 2.6]   |
    | 3   | forearm roll | -1  | 1   | [-2.97, 2.97] |
    | 4   | wrist pitch  | -1  | 1   | [-2.0, 2.0]   |
    | 5   | wrist roll   | -1  | 1   | [-2.97, 2.97] |

    ## Observation Space

    `Dict`:
    - `rgb`: `Box(0, 255, (height, width, 3), uint8)` from the first of `cameras`
      (default the third-person `"scene"` camera; `"wrist"` is the wrist camera).
    - `depth`, `segmentation` (optional): as in Track; the arm's pixels have id 100.
    - `proprio`: `Box(low, high, (15,), float32)`: joint angles [6] (rad, within their ranges), the last action
      [6], the end-effector position relative to the base divided by the reach [3].

    ## Rewards

    `reward = reward_reach + reward_ctrl`, in [-0.02, 1]:
    - `reward_reach = tolerance(dist, (0, success_distance), margin=0.5 * reach)`, `dist` the
      distance from the end-effector site to the target's centre, `success_distance` the
      target's bounding radius plus 5% of the reach;
    - `reward_ctrl = -0.02 * mean(action ** 2)`.

    ## Starting State

    Ready pose (arm raised above the base, gripper pointing forward and down) plus uniform joint noise of
    +-0.15 rad. The third-person camera looks at arm and path from 40 deg around and 30 deg
    above the generation camera's side. Scene time 0.

    ## Episode End

    Success (`info["success"]`): the end-effector came within `success_distance` of the
    target's centre. With `terminate_on_success=True` (default) the episode terminates
    then; it truncates at the end of the clip (6 s; 60 steps at 10 Hz).

    ## Arguments

    | Parameter | Type | Default | Description |
    |---|---|---|---|
    | `task` | `str \\| TaskSpec \\| dict \\| None` | `None` | task spec: a built-in name, a YAML path, a mapping; None = `"reach"` |
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
    | `cameras` | `tuple[str, ...] \\| None` | `None` | rig cameras to observe; None = `("scene",)`; also `"wrist"` |
    | `control_hz` | `float` | `10.0` | control rate; scene time advances 1 / control_hz per step |
    | `render_agent` | `bool \\| None` | `None` | draw the arm; None = task default (True) |
    | `terminate_on_success` | `bool` | `True` | terminate when the end-effector reaches the target |
    | `on_edit_error` | `str` | `"raise"` | failed edits: `"raise"`, or `"skip"` and go on with the unedited scene |
    | `render_mode` | `str \\| None` | `None` | `"rgb_array"` for `render()` |
    | `render_width` | `int` | `256` | `render()` frame width |
    | `render_height` | `int` | `256` | `render()` frame height |
    | `render_threads` | `int \\| None` | `1` | numba threads for this env's skinning and rendering (set per call, then restored); None = numba's default |
    | `render_lod` | `bool` | `False` | draw far object blocks as cached coarser merged Gaussians (`render.lod`, an approximation: off = exact images); CPU backend only |
    | `sim` | `MorphoSim \\| SimConfig \\| None` | `None` | the world: a `MorphoSim` or a `SimConfig`; None = `envs.config.DEFAULT_SIM_CONFIG` (oracle, detail 0.35) |
    | `task_params` | `dict \\| None` | `None` | overrides of `ReachTask.PARAMS` |

    Reset options: `prompt`, `scene_seed`, `target`, `edits`, `camera` (`position`,
    `look_at`, `fov_y_deg` of the third-person camera), `on_edit_error`.

    ## Version History

    - v0: initial version.
    """

    task_kind = "reach"
    config_defaults = {"terminate_on_success": True}
