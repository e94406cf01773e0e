"""`MorphoSimVectorEnv`: N MorphoSim worlds stepped in one process, all their cameras rendered in
one batched call (`render_batch`), registered as every id's Gymnasium `vector_entry_point`.

The batch holds N ordinary `MorphoSimEnv` instances and runs their own step in its two halves
(`_advance`: rig and clock; `_step_outcome`: reward, observation, info) around one batched
render of every env's `_render_request`, so env i with seed s gives exactly what a single env
with seed s gives (the batched kernel is bit-identical to the single render). Resets (rare) run
each env's own `reset`.
"""

from __future__ import annotations

from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from types import SimpleNamespace
from typing import Any, Callable, Mapping, Optional, Sequence

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import load_env_creator
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space, concatenate, create_empty_array, iterate

from morphosim_gym.render.api import PendingRender, open_batch, render_batch
from morphosim_gym.render.cpu.claimed import RenderHelpers
from morphosim_gym.render.cpu.pipeline import Workspace

from . import ENTRY_POINTS
from .options import ResetOptions
from .spaces import check_action
from .threads import numba_threads
from .vector_infos import InfoBatch, add_info
from .wrappers import LanguagePerturbation

__all__ = ["MorphoSimVectorEnv", "vector_entry_point"]

_RENDER_TIMEOUT_S = 600.0          # a batched render that takes longer is a hang: raise instead of waiting
SCHEDULERS = ("views", "numba")


class _Deferred(gym.Env):
    """The env under a per-env `LanguagePerturbation` in the batch: its `step` only advances the env
    (the batch renders and finishes the step) and hands the wrapper a placeholder result whose
    info receives the wrapper's keys; `reset` is the env's own."""

    def __init__(self, env: gym.Env, pending: list) -> None:
        self._env = env
        self._pending = pending
        self.observation_space, self.action_space = env.observation_space, env.action_space
        self.metadata = env.metadata

    @property
    def unwrapped(self) -> gym.Env:
        return self._env

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[dict, dict]:
        return self._env.reset(seed=seed, options=options)

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        info: dict = {}
        self._pending.append((action, info))
        return None, 0.0, False, False, info


class MorphoSimVectorEnv(VectorEnv):
    """N MorphoSim envs of one kind stepped together, their cameras rendered in one batched call.

    Args:
        num_envs: how many envs.
        kind: the task kind ("track", "reach", "find"); the registered ids set it.
        render_threads: threads of the batched render (None: numba's thread count,
            `NUMBA_NUM_THREADS`, all cores by default). Each env's own work (skinning, resets)
            keeps the env's `render_threads` (default 1).
        scheduler: how those threads share a step's render. "views" (default): this thread and
            `render_threads - 1` helper threads claim whole views (largest first) and render each
            one start to finish in one compiled call without the GIL; the helpers start as soon
            as a chunk's views are ready, while this thread prepares the next chunk or finishes
            the previous one, and this thread joins in when its Python work is done. "numba":
            one numba parallel region per stage (projection, binning, raster) over all views,
            as before 2026-12-02 (the helper thread of `pipeline` > 1 renders the whole chunk).
        backend: the batched render's backend ("cpu", or "gsplat" on a CUDA machine); None: the
            first env's `render_backend` (its sim's `config.render_backend`, "cpu" by default).
        perturbations: one `LanguagePerturbation` keyword dict (schedule, edits, probability,
            max_random_edits) or None per env: env i is stepped through its own
            `LanguagePerturbation`, exactly as `LanguagePerturbation(gym.make(id), **p)` would be,
            and its info carries "perturbations".
        env_kwargs: one dict of extra env arguments per env (over `kwargs`), or None.
        pipeline: how many chunks a step's envs are rendered in. With more than one, chunk c
            renders while this thread prepares chunk c + 1 (rig, skinning, cameras) and finishes
            chunk c - 1 (reward, observation, info). None: 1 (resets join the step's render).
            With the "numba" scheduler one worker thread renders each chunk alone (ask for it
            only with a thread-safe numba layer, tbb or omp); on 2 quiet cores that was slower
            than the serial batch (Track vector-8 1,264 vs 1,506 steps/s,
            `benchmarks/results/envs_quiet_2026-12-02b.json`). Results are the same either way
            (every view's image is independent of the batch and the thread it is rendered in).
        kwargs: env arguments (the fields of `EnvConfig`) for every env.

    Gymnasium's `autoreset_mode` is NEXT_STEP (as `SyncVectorEnv`'s default): the step after an
    env terminates or truncates resets it and returns its reset observation and info, with reward
    0 and both flags False. `reset(seed=s)` seeds env i with s + i; `options` is one dict for all
    envs (with an optional boolean "reset_mask") or a list of one dict (or None) per env.
    Per-env access: `envs[i]` (the `MorphoSimEnv`), `perturb(i, text)`, `call`, `get_attr`,
    `set_attr`.

    Examples:
        >>> venv = gym.make_vec("MorphoSim/Track-v0", 8, vectorization_mode="vector_entry_point")  # doctest: +SKIP
        >>> obs, info = venv.reset(seed=0, options=[{"edits": ["make the ball blue"]}] + [None] * 7)  # doctest: +SKIP
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": ["rgb_array"]}

    def __init__(self, num_envs: int, kind: str = "track", render_threads: Optional[int] = None,
                 backend: Optional[str] = None, perturbations: Optional[Sequence[Optional[Mapping[str, Any]]]] = None,
                 env_kwargs: Optional[Sequence[Optional[Mapping[str, Any]]]] = None, pipeline: Optional[int] = None,
                 scheduler: str = "views", **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"Expected num_envs as a positive integer, found {num_envs!r}")
        if kind not in ENTRY_POINTS:
            raise ValueError(f"Expected kind in {sorted(ENTRY_POINTS)}, found {kind!r}")
        if pipeline is not None and (isinstance(pipeline, bool) or not isinstance(pipeline, (int, np.integer))
                                     or pipeline < 1):
            raise ValueError(f"Expected pipeline as a positive integer or None, found {pipeline!r}")
        if scheduler not in SCHEDULERS:
            raise ValueError(f"Expected scheduler in {SCHEDULERS}, found {scheduler!r}")
        if render_threads is not None and (isinstance(render_threads, bool) or not isinstance(
                render_threads, (int, np.integer)) or render_threads < 1):
            raise ValueError(f"Expected render_threads as a positive integer or None, found {render_threads!r}")
        n = int(num_envs)
        per_env = _per_env(env_kwargs, n, "env_kwargs")
        perturbations = _per_env(perturbations, n, "perturbations")
        creator: Callable[..., gym.Env] = load_env_creator(ENTRY_POINTS[kind])
        self.num_envs = n
        self.render_threads = render_threads
        self.pipeline = None if pipeline is None else int(pipeline)
        self.scheduler = scheduler
        self._worker: Optional[ThreadPoolExecutor] = None
        self._helpers: Optional[RenderHelpers] = None
        self._workspaces: list = []              # staging buffers of the "views" scheduler, one per chunk
        self._gaussians: dict = {}               # per chunk: Gaussians to make room for (last steps' most, + 25%)
        self.envs = _make_envs(creator, kwargs, per_env)
        self.backend = backend if backend is not None else self.envs[0].render_backend
        self._pending: list[list] = [[] for _ in range(n)]
        self._steppers = [LanguagePerturbation(_Deferred(env, self._pending[i]), **perturbations[i])
                          if perturbations[i] is not None else None for i, env in enumerate(self.envs)]
        env0 = self.envs[0]
        self.render_mode = env0.render_mode
        self.metadata = dict(self.metadata, render_fps=env0.metadata.get("render_fps"))
        self.single_observation_space = env0.observation_space
        self.single_action_space = env0.action_space
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self._autoreset = np.zeros(n, dtype=bool)
        self._obs: list = [None] * n
        self._boxes: Optional[bool] = None       # the observation space is a dict of boxes (`_batched_obs`)

    # ================================================================== reset
    def reset(self, *, seed: int | Sequence[Optional[int]] | None = None,
              options: Optional[Mapping[str, Any] | Sequence[Optional[Mapping[str, Any]]]] = None
              ) -> tuple[dict, dict]:
        n = self.num_envs
        seeds = _seeds(seed, n)
        mask, per_env = _reset_options(options, n)
        infos: dict = {}
        for i in range(n):
            if not mask[i]:
                continue
            target = self._steppers[i] or self.envs[i]
            self._obs[i], info = target.reset(seed=seeds[i], options=per_env[i])
            self._autoreset[i] = False
            infos = self._add_info(infos, info, i)
        return self._batched_obs(), infos

    # ================================================================== step
    def step(self, actions: Any) -> tuple[dict, np.ndarray, np.ndarray, np.ndarray, dict]:
        n = self.num_envs
        st = _StepState(self._checked_actions(actions), n)
        stepping = [i for i in range(n) if not self._autoreset[i]]
        resetting = [i for i in range(n) if self._autoreset[i]]
        # resets of unwrapped envs join the first chunk's render (serial batch only); the others reset here
        joining = [i for i in resetting if self._steppers[i] is None] if self._pipeline_chunks() == 1 else []
        for i in resetting:
            if i not in joining:
                st.reset_out[i] = (self._steppers[i] or self.envs[i]).reset()
                st.infos.add(i, st.reset_out[i][1])
        # chunk by chunk: advance and build the render requests ("views": each view is handed to the
        # render helpers as soon as its env is advanced), start the chunk's render, finish the
        # previous chunk (reward, observation, info) while this one renders
        pending: deque = deque()
        chunks = self._chunks(stepping) or [[]]
        chunks[0] = joining + chunks[0]
        try:
            for c, chunk in enumerate(chunks):
                if not chunk:
                    continue
                sink = self._open(c, chunk)
                pending.append((chunk, None, sink))
                requests = self._prepare(chunk, st, sink)
                pending[-1] = (chunk, requests, self._launch(requests, c, sink))
                if len(pending) > 1:
                    self._finish(*pending.popleft(), st)
            while pending:
                self._finish(*pending.popleft(), st)
        except BaseException:
            for _, _, launched in pending:     # no helper may still write into a workspace the next step reuses
                if isinstance(launched, PendingRender):
                    launched.cancel()
            raise
        for i in resetting:
            self._obs[i] = st.reset_out[i][0]
        infos = st.infos.result(order=resetting + sorted(st.stepped))   # reset infos first, as each env's own
        self._autoreset = st.terms | st.truncs
        return self._batched_obs(), st.rewards, st.terms, st.truncs, infos

    def _checked_actions(self, actions: Any) -> list:
        """Every env's action, checked before any env is stepped (a bad one raises, naming its env,
        and no env moves): float64 clipped to [-1, 1], as `check_action` gives a single env."""
        n = self.num_envs
        shape = self.single_action_space.shape
        if all(w is None for w in self._steppers):
            batch = _checked_batch(actions, n, shape)
            if batch is not None:
                return list(batch)               # rows of one clipped float64 array
        acts = list(iterate(self.action_space, actions))
        if len(acts) != n:
            raise ValueError(f"Expected actions for {n} envs, found {len(acts)}")
        out = []
        for i, a in enumerate(acts):
            if self._steppers[i] is not None:
                out.append(a)                    # its wrapper sees the action as given; `_advance` checks it
                continue
            try:
                out.append(check_action(a, shape))
            except ValueError as exc:
                raise ValueError(f"Expected a valid action for env {i}: {exc}; no env was stepped") from None
        return out

    def _finish(self, chunk: list, requests: list, launched: Any, st: "_StepState") -> None:
        """The rest of the step of a chunk's envs once its render is done (`_finish_env`). With the
        "views" scheduler each env is finished as soon as its own views are rendered, in whatever
        order that is (this thread renders views from the last while the helpers render them from
        the first), while the helpers render other envs' views."""
        if isinstance(launched, PendingRender):
            left, k = [], 0
            for i, request in zip(chunk, requests):
                left.append((i, request, k, k + len(request[1])))
                k += len(request[1])
            while left:                          # first the envs whose views are done, whichever they are
                i, request, lo, hi = left.pop(launched.first_ready([(lo, hi) for _, _, lo, hi in left]))
                self._finish_env(i, self._rendered([i], [request], launched.partial(lo, hi))[0], st)
            return
        outs = launched.result(timeout=_RENDER_TIMEOUT_S) if isinstance(launched, Future) else launched
        for i, rendered in zip(chunk, self._rendered(chunk, requests, outs)):
            self._finish_env(i, rendered, st)

    def _finish_env(self, i: int, rendered: tuple, st: "_StepState") -> None:
        """Env i's reward, flags, observation and info (into `st`; its info into the step's
        `InfoBatch` at once), or the end of its reset (into `st.reset_out`)."""
        if i in st.checked:
            self._obs[i], st.rewards[i], st.terms[i], st.truncs[i], info = self.envs[i]._step_outcome(
                st.checked[i], rendered)
            info.update(st.extra[i])
            st.stepped.append(i)
        else:
            st.reset_out[i] = self.envs[i]._reset_end(rendered)
            info = st.reset_out[i][1]
        st.infos.add(i, info)

    def _advance(self, i: int, action: Any) -> tuple[np.ndarray, dict]:
        """Env i's step up to its render (through its `LanguagePerturbation` if any): the checked
        action and the info keys its wrapper added."""
        env = self.envs[i]
        wrapper = self._steppers[i]
        if wrapper is None:                      # checked already (`_checked_actions`)
            env._advance(action)
            return action, {}
        pending = self._pending[i]
        pending.clear()
        wrapper.step(action)
        action, extra = pending.pop()
        a = check_action(action, env.action_space.shape)
        env._advance(a)
        return a, extra

    def _chunks(self, indices: list) -> list:
        """The stepping envs in `pipeline` contiguous chunks (one chunk: no worker thread)."""
        k = max(1, min(self._pipeline_chunks(), len(indices)))
        if k == 1:
            return [list(indices)] if indices else []
        bounds = np.linspace(0, len(indices), k + 1).round().astype(int)
        return [indices[bounds[j]:bounds[j + 1]] for j in range(k) if bounds[j + 1] > bounds[j]]

    def _pipeline_chunks(self) -> int:
        return 1 if self.pipeline is None else self.pipeline   # None: one chunk (see __init__)

    def _prepare(self, chunk: list, st: "_StepState", sink: Optional[PendingRender]) -> list:
        """Advance each env of the chunk (`_advance`: checked action and wrapper keys into
        `st.checked` and `st.extra`), or begin its reset if it is resetting (it stays out of `checked`), and build
        its `_render_request`, whose views go into `sink` at once when given (then closed); one
        `numba_threads` per run of envs with the same `render_threads` (it is not free: a lock and
        two thread-count changes)."""
        requests = []
        for threads, run in _runs(chunk, [self.envs[i].config.render_threads for i in chunk]):
            with numba_threads(threads):
                for i in run:
                    env = self.envs[i]
                    if self._autoreset[i]:
                        gym.Env.reset(env)                 # as env.reset() does before its own work
                        env._reset_begin(ResetOptions.parse(None))
                    else:
                        st.checked[i], st.extra[i] = self._advance(i, st.acts[i])
                    request = env._render_request(env.world.t)
                    requests.append(request)
                    if sink is not None:
                        sources, cams, bg, sky = request
                        for cam in cams:
                            sink.add((sources, cam, bg, sky))
        if sink is not None:
            sink.close()
        return requests

    def _open(self, slot: int, chunk: list) -> Optional[PendingRender]:
        """The "views" scheduler's open batched render of a chunk (None for "numba"), sized for its
        views and pixels and for the most Gaussians its slot has seen."""
        if self.scheduler != "views":
            return None
        while len(self._workspaces) <= slot:
            self._workspaces.append(Workspace())
        views = pixels = 0
        for i in chunk:
            env = self.envs[i]
            views += len(env._render_cams)
            pixels += len(env._render_cams) * env.config.width * env.config.height
        return open_batch(helpers=self._render_helpers(), backend=self.backend, lod=self.envs[0].config.render_lod,
                          workspace=self._workspaces[slot], capacity=(views, self._gaussians.get(slot, 0), pixels))

    def _launch(self, requests: list, slot: int = 0, sink: Optional[PendingRender] = None) -> Any:
        """The batched render of these requests, started: `sink` itself (scheduler "views", already
        closed), else a `Future` from the worker thread when pipelined (more than one chunk), else
        the outputs themselves."""
        if sink is not None:
            self._gaussians[slot] = max(self._gaussians.get(slot, 0), int(1.25 * sink.staged[1]))
            return sink
        views = [(sources, cam, bg, sky) for sources, cams, bg, sky in requests for cam in cams]
        if self._pipeline_chunks() == 1:
            return self._render_views(views)
        if self._worker is None:
            self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="morphosim-vector-render")
        return self._worker.submit(self._render_views, views)

    def _render_helpers(self) -> RenderHelpers:
        """The helper threads of the "views" scheduler (`render_threads - 1` of them)."""
        if self._helpers is None:
            import numba

            threads = self.render_threads if self.render_threads is not None else numba.config.NUMBA_NUM_THREADS
            self._helpers = RenderHelpers(max(0, int(threads) - 1))
        return self._helpers

    def _render_views(self, views: list) -> list:
        with numba_threads(self.render_threads):
            return render_batch(views, backend=self.backend, lod=self.envs[0].config.render_lod)

    def _rendered(self, indices: Sequence[int], requests: list, outs: list) -> list:
        """`_render`'s result for each of these envs, from the batched render of their requests."""
        rendered, k = [], 0
        for i, (_, cams, _, _) in zip(indices, requests):
            mine = outs[k:k + len(cams)]
            k += len(cams)
            out = SimpleNamespace(rgb=[o.rgb for o in mine], depth=[o.depth for o in mine],
                                  instance=[o.instance for o in mine])
            rendered.append(self.envs[i]._rendered(cams, out, self.envs[i].world.t))
        return rendered

    def _add_info(self, vector_infos: dict, env_info: dict, env_num: int) -> dict:
        """`VectorEnv._add_info`, cheaper (`vector_infos.add_info`)."""
        return add_info(vector_infos, env_info, env_num, self.num_envs)

    def _batched_obs(self) -> dict:
        """Gymnasium's `concatenate` of the envs' observations: for a dict of boxes (every env's)
        one `np.stack` per key into an array of the space's dtype, without its dispatch."""
        space = self.single_observation_space
        if self._boxes is None:
            self._boxes = isinstance(space, gym.spaces.Dict) and all(
                type(sub) is gym.spaces.Box for sub in space.spaces.values())
        if not self._boxes:
            return concatenate(space, self._obs, create_empty_array(space, self.num_envs))
        n = self.num_envs
        return {key: np.stack([o[key] for o in self._obs], out=np.empty((n, *sub.shape), sub.dtype))
                for key, sub in space.spaces.items()}

    # ================================================================== per-env access
    def perturb(self, i: int, text: str) -> bool:
        """Apply a language edit to env i's scene now (`MorphoSimEnv.perturb`)."""
        return self.envs[self._index(i)].perturb(text)

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple:
        """Call (or read) attribute `name` of every env; a tuple of the results."""
        out = []
        for env in self.envs:
            attr = getattr(env, name)
            out.append(attr(*args, **kwargs) if callable(attr) else attr)
        return tuple(out)

    def get_attr(self, name: str) -> tuple:
        """Attribute `name` of every env."""
        return tuple(getattr(env, name) for env in self.envs)

    def set_attr(self, name: str, values: Any) -> None:
        """Set attribute `name` of every env (one value for all, or a list of one per env)."""
        if not isinstance(values, (list, tuple)):
            values = [values] * self.num_envs
        if len(values) != self.num_envs:
            raise ValueError(f"Expected {self.num_envs} values for set_attr({name!r}), found {len(values)}")
        for env, value in zip(self.envs, values):
            setattr(env, name, value)

    def render(self) -> Optional[tuple]:
        """Each env's `render()` frame (with render_mode="rgb_array")."""
        if self.render_mode is None:
            return None
        return tuple(env.render() for env in self.envs)

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_worker"] = None               # a thread pool does not copy; the copy starts its own
        state["_helpers"] = None
        state["_workspaces"] = []
        return state

    def close_extras(self, **kwargs: Any) -> None:
        if self._worker is not None:
            self._worker.shutdown(wait=True)
            self._worker = None
        if self._helpers is not None:
            self._helpers.close()
            self._helpers = None
        for env in self.envs:
            env.close()

    def _index(self, i: int) -> int:
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 0 <= int(i) < self.num_envs:
            raise ValueError(f"Expected an env index in [0, {self.num_envs}), found {i!r}")
        return int(i)


class _StepState:
    """What one vector step gathers as its envs are advanced and finished."""

    __slots__ = ("acts", "checked", "extra", "rewards", "terms", "truncs", "reset_out", "stepped", "infos")

    def __init__(self, acts: list, n: int) -> None:
        self.acts = acts                         # each env's action as checked (`_checked_actions`)
        self.checked: dict = {}                  # stepping env -> its action as its env takes it
        self.extra: dict = {}                    # stepping env -> info keys of its `LanguagePerturbation`
        self.rewards = np.zeros(n, dtype=np.float64)
        self.terms = np.zeros(n, dtype=bool)
        self.truncs = np.zeros(n, dtype=bool)
        self.reset_out: dict = {}                # resetting env -> (observation, info)
        self.stepped: list = []                  # stepping envs, in the order they were finished
        self.infos = InfoBatch(n)                # every env's info, batched as it comes


def vector_entry_point(kind: str) -> Callable[..., MorphoSimVectorEnv]:
    """The `vector_entry_point` of a task kind's ids: `MorphoSimVectorEnv` with that kind."""
    if kind not in ENTRY_POINTS:
        raise ValueError(f"Expected kind in {sorted(ENTRY_POINTS)}, found {kind!r}")

    def make(num_envs: int = 1, **kwargs: Any) -> MorphoSimVectorEnv:
        return MorphoSimVectorEnv(num_envs, kind=kind, **kwargs)

    make.__name__ = f"vector_{kind}"
    return make


def __getattr__(name: str) -> Any:
    # "morphosim_gym.envs.native_vector:vector_<kind>" (the registered vector entry points)
    if name.startswith("vector_") and name[len("vector_"):] in ENTRY_POINTS:
        return vector_entry_point(name[len("vector_"):])
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _runs(items: list, keys: list) -> list:
    """`items` cut into runs of consecutive items with equal keys: [(key, [items...]), ...]."""
    runs: list = []
    for item, key in zip(items, keys):
        if runs and runs[-1][0] == key:
            runs[-1][1].append(item)
        else:
            runs.append((key, [item]))
    return runs


def _checked_batch(actions: Any, n: int, shape: tuple) -> Optional[np.ndarray]:
    """`check_action` of every row of a finite [n, *shape] numeric array at once (the same float64
    values, clipped); None for anything else (then each env's action is checked on its own, and
    the first bad one named)."""
    if not isinstance(actions, np.ndarray) or actions.shape != (n, *shape) or actions.dtype.kind not in "fiu":
        return None
    a = np.asarray(actions, dtype=np.float64)
    if not np.isfinite(a).all():
        return None
    return np.clip(a, -1.0, 1.0)


def _make_envs(creator: Callable[..., gym.Env], kwargs: Mapping[str, Any],
               per_env: Sequence[Optional[Mapping[str, Any]]]) -> list:
    """The batch's envs; an env whose `sim` argument is the first env's (the same object, or both
    absent) shares the first env's `SceneSource`, so a pool is built once and pooled scenes (and
    the posed Gaussians they cache) are one object for all the envs that draw them."""
    envs: list = []
    first_sim = None
    for own in per_env:
        merged = {**kwargs, **(own or {})}
        if envs and merged.get("sim") is first_sim:
            merged["_scene_source"] = envs[0]._source
        envs.append(creator(**merged))
        if len(envs) == 1:
            first_sim = merged.get("sim")
    return envs


def _per_env(values: Optional[Sequence[Any]], n: int, name: str) -> list:
    if values is None:
        return [None] * n
    values = list(values)
    if len(values) != n or not all(v is None or isinstance(v, Mapping) for v in values):
        raise ValueError(f"Expected {name} as a list of {n} dicts (or None), found {values!r}")
    return [None if v is None else dict(v) for v in values]


def _seeds(seed: Any, n: int) -> list:
    if seed is None:
        return [None] * n
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
        return [int(seed) + i for i in range(n)]
    seeds = list(seed)
    if len(seeds) != n:
        raise ValueError(f"Expected a seed, None or a list of {n} seeds, found {len(seeds)} seeds")
    return seeds


def _reset_options(options: Any, n: int) -> tuple[np.ndarray, list]:
    """(which envs to reset, each one's options) of `reset(options=...)`."""
    if options is None:
        return np.ones(n, dtype=bool), [None] * n
    if isinstance(options, Mapping):
        opts = dict(options)
        mask = opts.pop("reset_mask", None)
        if mask is None:
            mask = np.ones(n, dtype=bool)
        mask = np.asarray(mask)
        if mask.shape != (n,) or mask.dtype != np.bool_ or not mask.any():
            raise ValueError(f"Expected options['reset_mask'] as a bool array of shape ({n},) with a True, "
                             f"found {mask!r}")
        return mask, [opts or None] * n
    return np.ones(n, dtype=bool), _per_env(options, n, "options")
