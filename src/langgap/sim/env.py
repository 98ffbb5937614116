"""One LIBERO environment for one LangGap task, with explicit options and fixed init states.

Conventions (the ones public LIBERO checkpoints were trained with; see the docs, docs/protocol.md "Conventions"):

* `reset(init_index, seed)` seeds NumPy's global generator (LIBERO samples fixture placements from
  it), resets, and *then* applies init state `init_index`; it returns the t0 observation and sets
  `t0_hash`. Same init index and seed give the same t0 in every sibling task of a scene.
* Images are upright: LIBERO renders upside down, we return `raw[::-1, ::-1]` (rotated 180 degrees),
  which is the orientation of the `lerobot/libero` and openpi LIBERO training data.
* `state` is 8-D float32: end-effector position (3), end-effector orientation as axis-angle (3),
  and the two gripper finger joints (2).
* Images show the state robosuite's observables sample (its camera observables included, the way
  LIBERO's training data was recorded): after the second-to-last physics substep of a control step,
  not the last. A caller names the cameras it will read after a step (`step(..., capture=...)`, and
  `settle` for the first look); they are rendered inside the step at that substep, once each.
  A camera not captured is rendered when asked, from the state as it is then (right after a reset or
  a restored state, where robosuite renders the same; one substep late after an uncaptured step).
* Nothing is rendered unless a camera is requested.
* An episode starts as in a freshly built LIBERO environment (what openpi's LIBERO example runs):
  MuJoCo's solver warm start is cleared where a hard reset clears it, by robosuite's reset before its
  forward passes (a soft reset makes the two a new rendering simulator makes, too: `_reset_as_fresh_sim`),
  and never again: not at the init state, not after settling
  (`langgap.stack.CONVENTIONS`, recorded in results).
* Episode length is capped here (`max_steps` policy steps after `settle()`), never by robosuite's
  horizon, which raises on the step after it.
"""

from __future__ import annotations

import hashlib
import math
import os
from dataclasses import dataclass, field

import numpy as np

from langgap.bddl import Predicate
from langgap.catalog.files import TaskFiles, task_files
from langgap.catalog.task import Task
from langgap.errors import InitStateError, SimulationError
from langgap.goals import Goal, GoalProgress, holds_now
from langgap.sim.privileged_schema import PrivilegedState
from langgap.sim.resting import Placements
from langgap.stack import DEFAULT_SEED_SCHEME, DEFAULT_STEPPING
from langgap.vocabulary import SeedScheme, Stepping

CAMERAS = ("agentview", "robot0_eye_in_hand")
SETTLE_STEPS = 10
SETTLE_ACTION = np.array([0, 0, 0, 0, 0, 0, -1], dtype=np.float64)
ACTION_DIM = 7
# Every action component's range: robosuite's OSC_POSE controller clips its input to [-1, 1] (input_max 1)
# and the gripper is -1 open, +1 closed, so a larger value moves the robot no further than the limit.
ACTION_LIMIT = 1.0
# The robosuite observable whose sampling marks the substep at which robosuite samples every observable
# (its cameras too): the end-effector position, part of the state LangGap sends.
_SAMPLED_WITH = "robot0_eef_pos"
# The forward passes a hard reset of a rendering LIBERO env makes at the model's reference configuration:
# robosuite's `_initialize_sim`, then `MjRenderContext.__init__` for the new simulator's offscreen context.
_FRESH_SIM_FORWARDS = 2
# Far above any episode: robosuite's own horizon must never be what ends an episode.
_ROBOSUITE_HORIZON = 1_000_000


def configure_rendering() -> None:
    """Select headless EGL rendering unless the user chose a backend; must run before MuJoCo loads."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    if os.environ["MUJOCO_GL"] in ("egl", "osmesa"):
        os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])


@dataclass(frozen=True)
class EnvOptions:
    """How an environment is built. The defaults render nothing and reset softly."""

    cameras: tuple[str, ...] = ()
    image_size: int = 256
    reflection: bool = True
    hard_reset: bool = False
    privileged: bool = False
    # how physics substeps are computed (`Stepping`: exact, fast or robosuite's own code; sim/stepping.py)
    stepping: str = DEFAULT_STEPPING
    # how `reset(init_index, seed)` seeds the fixture placement (`SeedScheme`)
    seed_scheme: str = DEFAULT_SEED_SCHEME

    def __post_init__(self) -> None:
        unknown = [c for c in self.cameras if c not in CAMERAS]
        if unknown:
            raise SimulationError(f"unknown camera(s) {unknown}; LIBERO has {', '.join(CAMERAS)}")
        if len(set(self.cameras)) != len(self.cameras):
            raise SimulationError(f"camera listed twice: {list(self.cameras)}")
        if self.stepping not in tuple(Stepping):
            raise SimulationError(f"unknown stepping {self.stepping!r} (known: {', '.join(Stepping)})")
        if self.seed_scheme not in tuple(SeedScheme):
            raise SimulationError(f"unknown seed scheme {self.seed_scheme!r} (known: {', '.join(SeedScheme)})")
        if not 16 <= self.image_size <= 1024:
            raise SimulationError(f"image size must be in 16..1024, got {self.image_size}")

    @property
    def renders(self) -> bool:
        return bool(self.cameras)


class CameraNotDeclared(KeyError):
    """A policy read a camera its spec does not declare: only declared cameras are rendered."""

    def __str__(self) -> str:
        return str(self.args[0])  # KeyError quotes its argument, which is a sentence here


class CameraImages(dict):
    """An observation's images by camera; reading a camera that is not there names the spec that leaves it out."""

    def __missing__(self, camera: str):
        declared = ", ".join(self) or "none"
        raise CameraNotDeclared(
            f"camera {camera!r} is not rendered: the policy's spec declares {declared}; declare every camera act "
            "reads in PolicySpec(cameras=...)"
        )


@dataclass
class Observation:
    """What the environment shows a policy at one step.

    Attributes:
        state: The 8-D float32 robot state: end-effector position (3), end-effector orientation as axis-angle
            (3), the two gripper finger joints (2).
        images: An upright uint8 image (H, W, 3) per camera the policy's spec names.
        privileged: The simulator state (`EnvOptions.privileged`), for a policy whose spec `sees_state`.
        instruction: The instruction in force at this step (it may change mid-episode); None: the reset
            context's stands.
    """

    state: np.ndarray
    images: dict[str, np.ndarray] = field(default_factory=dict)
    privileged: PrivilegedState | None = None
    instruction: str | None = None


def quat_to_axis_angle(quat_xyzw: np.ndarray) -> np.ndarray:
    """robosuite's `quat2axisangle` (what LIBERO training data used), without mutating its input."""
    w = min(max(float(quat_xyzw[3]), -1.0), 1.0)
    den = math.sqrt(1.0 - w * w)
    if math.isclose(den, 0.0):
        return np.zeros(3)
    return np.asarray(quat_xyzw[:3], dtype=np.float64) * 2.0 * math.acos(w) / den


def state_from_robosuite(obs: dict) -> np.ndarray:
    """The 8-D state from robosuite's observation dict."""
    return np.concatenate(
        [obs["robot0_eef_pos"], quat_to_axis_angle(obs["robot0_eef_quat"]), obs["robot0_gripper_qpos"]]
    ).astype(np.float32)


class TaskEnv:
    """A LIBERO environment for `task`, built from its files (`files`: resolved here when not given). Close it
    (or use it as a context manager) before exit."""

    def __init__(self, task: Task, options: EnvOptions | None = None, files: TaskFiles | None = None):
        self.task = task
        self.options = options or EnvOptions()
        self.files = task_files(task) if files is None else files
        self.t0_hash: str | None = None
        self.steps = 0
        self.renders = 0  # camera images rendered since construction (what benchmarks and tests count)
        self._captured: dict[str, np.ndarray] = {}  # images of the current state, rendered inside its step
        self._stream: tuple[int, int, tuple] | None = None  # openpi seed scheme: (seed, resets drawn, NumPy state)
        self._raw_obs: dict | None = None
        self._progress = GoalProgress(task.goal)
        self._holds = False  # the task's goal, as of the last observed step
        self._truth: dict[Predicate, bool] = {}  # atoms read in the state `_truth_of` names
        self._truth_of: tuple | None = None
        configure_rendering()
        # Imported here: robosuite and MuJoCo load only when an environment is built (after the GL choice).
        from libero.libero.envs.env_wrapper import ControlEnv

        from langgap.sim.contacts import ContactIndex
        from langgap.sim.stepping import FastStepping

        kwargs = dict(
            bddl_file_name=str(self.files.bddl),
            has_renderer=False,
            has_offscreen_renderer=self.options.renders,
            use_camera_obs=False,  # we render on demand in observe(), never per physics step
            ignore_done=True,
            horizon=_ROBOSUITE_HORIZON,
            hard_reset=self.options.hard_reset,
        )
        if self.options.renders:
            kwargs.update(camera_names=list(self.options.cameras))
        try:
            self._env = ControlEnv(**kwargs)
        except Exception as exc:  # LIBERO raises bare asserts and XML errors alike
            raise SimulationError(f"cannot build env for {task.id}: {type(exc).__name__}: {exc}") from exc
        self._inner = self._env.env
        ContactIndex.install(self._inner)
        self._placements = Placements(self._inner)  # what `(Moved o)` reads: step 0's places, what the hand moved
        if self.options.stepping != Stepping.ROBOSUITE:
            FastStepping.install(self._inner, fast=self.options.stepping == Stepping.FAST)

    @property
    def init_states(self) -> np.ndarray:
        """The fixed init states the task starts from (`TaskFiles.init_states`)."""
        return self.files.init_states

    # -- lifecycle ---------------------------------------------------------------------------

    def can_switch_to(self, task: Task, files: TaskFiles | None = None) -> bool:
        """Whether `task` (its `files`: resolved here when not given) is set in this env's scene with the same
        init states, so the simulator can be kept (a package's task may ship init states of its own beside its
        source's: LIBERO-PRO's do)."""
        return (task.suite, task.scene_task) == (self.task.suite, self.task.scene_task) and self.files.same_start(
            task_files(task) if files is None else files
        )

    def switch_task(self, task: Task, files: TaskFiles | None = None) -> None:
        """Evaluate `task` (its `files`: resolved here when not given) from now on. Same-scene tasks differ only
        in goal and instruction, which LangGap evaluates itself, so the simulator (seconds to build) is reused
        as it is."""
        files = task_files(task) if files is None else files
        if not self.can_switch_to(task, files):
            raise SimulationError(f"cannot switch {self.task.id} to {task.id}: not the same scene and init states")
        self.task = task
        self.files = files
        self._progress = GoalProgress(task.goal)
        self._holds = False

    def __enter__(self) -> TaskEnv:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Release the simulator and its GL context (avoids EGL errors at interpreter exit)."""
        env = getattr(self, "_env", None)
        if env is not None:
            self._make_render_context_current()  # MuJoCo frees its GL objects in whatever context is current
            env.close()
            self._env = None

    @property
    def sim(self):
        """The underlying robosuite MjSim (privileged access, for oracles and diagnostics)."""
        return self._inner.sim

    @property
    def robosuite_env(self):
        """The underlying LIBERO/robosuite environment (privileged access)."""
        return self._inner

    @property
    def robosuite_observation(self) -> dict:
        """robosuite's latest observation dict (proprioception; no images), for adapters that need its raw form."""
        if self._raw_obs is None:
            raise SimulationError("no observation before reset()")
        return self._raw_obs

    # -- episode -----------------------------------------------------------------------------

    def reset(self, init_index: int | None, seed: int = 0, *, render: bool = True) -> Observation:
        """Reset, then apply init state `init_index`; returns the t0 observation.

        `init_index=None` keeps the placement LIBERO's samplers draw from the BDDL regions (seeded by
        `seed`, fixtures included): a fresh start that is none of the fixed init states (demonstrations).
        `render=False` leaves the images out of the returned observation: a caller that settles before
        anyone looks (an episode) saves a render of every camera (about 90 ms each at 256², software GL).
        With the `openpi` seed scheme, `seed` is the plan's seed (run seed + init index, as in the default
        scheme) and the placement is the one openpi's example draws in episode `init_index` of a task seeded
        with the run seed.
        """
        if init_index is not None and not 0 <= init_index < len(self.init_states):
            raise InitStateError(
                f"init index {init_index} out of range: {self.task.id} has {len(self.init_states)} init states"
            )
        if self.options.seed_scheme == SeedScheme.OPENPI and init_index is not None and seed < init_index:
            raise SimulationError(
                f"{SeedScheme.OPENPI} seed scheme: seed {seed} is below init index {init_index} (run seed + k)"
            )
        # LIBERO samples object and fixture placements (fixtures are not part of an init state) from
        # NumPy's global RNG.
        openpi_stream = self.options.seed_scheme == SeedScheme.OPENPI and init_index is not None
        if openpi_stream:
            self._draw_openpi_stream(seed - init_index, init_index)
        else:
            np.random.seed(seed)
        if init_index is None:
            # A soft reset's placement depends on the state it starts from (LIBERO places an object on
            # another where that one was), so a sampled start rebuilds the model: the seed alone decides it.
            self._inner.hard_reset = True
            try:
                self._raw_obs = self._env.reset()
            finally:
                self._inner.hard_reset = self.options.hard_reset
        else:
            self._raw_obs = self._reset_as_fresh_sim()
            if openpi_stream:
                self._stream = (seed - init_index, init_index + 1, np.random.get_state())
        # robosuite keeps the gripper's commanded opening across soft resets (only a new model zeroes it);
        # without this, an episode would start with the previous episode's gripper command.
        for robot in self._inner.robots:
            robot.gripper.current_action = np.zeros(robot.gripper.dof)
        if init_index is not None:
            self._apply_init_state(init_index)
        # MuJoCo's solver warm start is not touched here: robosuite's reset zeroed it (mj_resetData, or a new
        # MjData on a hard reset) before the forward passes a fresh LIBERO environment makes, so it is what a fresh
        # environment has at this init state, whatever ran before (clearing it again would depart from one).
        self._captured = {}
        self.t0_hash = self.state_hash()
        self.steps = 0
        self._restart_goal()
        self._reapply_render_flags()
        return self.observe(None if render else ())

    def _reset_as_fresh_sim(self) -> dict:
        """robosuite's soft reset, with the two forward passes a hard reset of openpi's `OffScreenRenderEnv` makes
        on its new simulator before placing anything (robosuite's `_initialize_sim`, then the new offscreen render
        context's) made after `mj_resetData` too: each leaves MuJoCo's solver warm start from which the next
        forward pass starts, so without them a libero_object scene's settled start differs from openpi's example
        in the last bits (spatial, goal and libero_10 scenes settle the same either way: docs/parity.md). They are
        made whether this env renders or not, so an episode's physics never depends on its cameras."""
        sim = self.sim

        def reset_as_new_simulator() -> None:
            type(sim).reset(sim)
            for _ in range(_FRESH_SIM_FORWARDS):
                sim.forward()

        sim.reset = reset_as_new_simulator
        try:
            return self._env.reset()
        finally:
            del sim.reset  # back to robosuite's method

    def _draw_openpi_stream(self, stream_seed: int, resets: int) -> None:
        """Put NumPy's global RNG where openpi's LIBERO example has it before episode `resets` of a task: seeded
        once with `stream_seed`, then `resets` resets' placement draws (a soft reset draws what a hard one
        does). Episodes run in order continue from the previous one's state instead of redrawing."""
        seed, drawn, state = self._stream or (None, 0, None)
        if seed != stream_seed or drawn > resets:
            np.random.seed(stream_seed)
            drawn = 0
        else:
            np.random.set_state(state)
        for _ in range(resets - drawn):
            self._env.reset()

    def _apply_init_state(self, init_index: int) -> None:
        state = self.init_states[init_index]
        self._raw_obs = self._env.set_init_state(state)
        applied = self._env.get_sim_state()
        if applied.shape != state.shape or not np.array_equal(applied, state):
            raise InitStateError(
                f"{self.task.id}: init state {init_index} did not apply (state size "
                f"{applied.shape[0]} vs {state.shape[0]})"
            )

    def nearest_init_distance(self) -> float:
        """Max-abs distance of the current positions (qpos) to the closest of the task's fixed init states."""
        nq = self.sim.model.nq
        qpos = self.sim_state()[1 : 1 + nq]
        return float(np.abs(self.init_states[:, 1 : 1 + nq] - qpos).max(axis=1).min())

    def settle(self, steps: int = SETTLE_STEPS, *, capture: tuple[str, ...] = ()) -> None:
        """The no-op steps (gripper open) that let objects come to rest; not counted, not shown to policies.

        The solver's warm start is left as the steps leave it, as in a fresh LIBERO environment.
        `capture`: the cameras the first look after settling reads, rendered inside the last step (see `step`).
        """
        for i in range(steps):
            self._raw_obs = self._step_sim(SETTLE_ACTION, capture if i == steps - 1 else ())
        self._restart_goal()

    def _restart_goal(self) -> None:
        # The goal's history (when each part of an ordered goal first held) starts at the state the
        # policy first sees: step 0, after settling (or a restored state); so does where things started.
        self._placements.restart()
        self._truth_of = None  # atoms read before (a `Moved` among them) measured from another start
        self._progress = GoalProgress(self.task.goal)
        self._holds = self._progress.observe(0, self.predicate_holds)

    def _forget_solver_history(self) -> None:
        # MuJoCo warm-starts its constraint solver from the previous step's accelerations, which are not
        # part of the state LIBERO saves or restores. Left alone, an episode would depend (at the solver's
        # tolerance, enough to flip a grasp) on whatever ran before it in the same process.
        self.sim.data.qacc_warmstart[:] = 0.0

    def step(self, action: np.ndarray, *, capture: tuple[str, ...] = ()) -> bool:
        """Apply one 7-D action (OSC_POSE delta + gripper); returns whether the task goal holds now.

        `capture`: the cameras the caller will read before the next step, rendered inside this step at
        the substep where robosuite samples its observables (`observe` and `render` then return them).
        """
        if self.steps >= self.task.max_steps:
            raise SimulationError(f"{self.task.id}: episode is over ({self.task.max_steps} steps)")
        action = np.asarray(action, dtype=np.float64)
        if action.shape != (ACTION_DIM,) or not np.all(np.isfinite(action)):
            raise SimulationError(f"action must be 7 finite numbers, got shape {action.shape}")
        self._raw_obs = self._step_sim(action, capture)
        self.steps += 1
        self._placements.observe()
        self._holds = self._progress.observe(self.steps, self.predicate_holds)
        return self._holds

    def _step_sim(self, action: np.ndarray, capture: tuple[str, ...]) -> dict:
        """One control step through robosuite; renders `capture` at the substep its observables sample."""
        self._captured = {}
        missing = [c for c in capture if c not in self.options.cameras]
        if missing:
            raise SimulationError(f"camera(s) {missing} were not enabled for this env")
        if not capture:
            return self._env.step(action)[0]
        inner = self._inner
        sample = inner._update_observables
        captured: dict[str, np.ndarray] = {}

        def update_observables(force: bool = False) -> None:
            before = inner._obs_cache.get(_SAMPLED_WITH)
            sample(force)
            if inner._obs_cache.get(_SAMPLED_WITH) is not before:  # robosuite sampled at this substep
                captured.update((camera, self._render_now(camera)) for camera in capture)

        inner._update_observables = update_observables
        try:
            obs = self._env.step(action)[0]
        finally:
            del inner._update_observables  # back to robosuite's method
        if len(captured) != len(capture):
            raise SimulationError(f"robosuite sampled no observation in this step ({_SAMPLED_WITH} unchanged)")
        self._captured = captured
        return obs

    @property
    def truncated(self) -> bool:
        """True once the task's step limit is reached."""
        return self.steps >= self.task.max_steps

    def success(self) -> bool:
        """Whether this task's goal holds now, as judged over the episode so far (an ordered goal needs its
        parts to have held in order since step 0)."""
        return self._holds

    def goal_holds(self, goal: Goal) -> bool:
        """Whether `goal` holds in the current state, order ignored (`langgap.goals.holds_now`)."""
        return holds_now(goal, self.predicate_holds)

    def predicate_holds(self, predicate: Predicate) -> bool:
        """Whether one atom holds in the current state (LIBERO's predicate; `Moved`, LangGap's, from where
        things were at step 0: `langgap.sim.resting`). Each atom is read once per state: the task's goal
        and every scene goal watched beside it share atoms."""
        data = self.sim.data._data
        state = (id(data), data.time, data.qpos.tobytes())
        if state != self._truth_of:
            self._truth, self._truth_of = {}, state
        value = self._truth.get(predicate)
        if value is None:
            value = self._truth[predicate] = self._evaluate(predicate)
        return value

    def _evaluate(self, predicate: Predicate) -> bool:
        if predicate.libero:
            return bool(self._inner._eval_predicate(predicate.as_libero()))
        return self._placements.moved(predicate.args[0])

    # -- observations ------------------------------------------------------------------------

    def observe(self, cameras: tuple[str, ...] | None = None) -> Observation:
        """The current observation; renders the requested cameras (default: the env's) once each."""
        if self._raw_obs is None:
            raise SimulationError("observe() before reset()")
        wanted = self.options.cameras if cameras is None else cameras
        missing = [c for c in wanted if c not in self.options.cameras]
        if missing:
            raise SimulationError(f"camera(s) {missing} were not enabled for this env")
        images = CameraImages({c: self.render(c) for c in wanted})
        privileged = None
        if self.options.privileged:
            from langgap.sim.privileged import privileged_state

            privileged = privileged_state(self)
        return Observation(state=state_from_robosuite(self._raw_obs), images=images, privileged=privileged)

    def render(self, camera: str) -> np.ndarray:
        """One upright uint8 image (H, W, 3) from `camera`: the one captured in the last step if it was,
        else rendered now."""
        captured = self._captured.get(camera)
        return captured if captured is not None else self._render_now(camera)

    def _render_now(self, camera: str) -> np.ndarray:
        size = self.options.image_size
        self.renders += 1
        self._make_render_context_current()
        raw = self.sim.render(camera_name=camera, width=size, height=size)
        return np.ascontiguousarray(raw[::-1, ::-1])

    def _make_render_context_current(self) -> None:
        # robosuite makes a GL context current only when it creates one, and MuJoCo draws into (and frees
        # GL objects of) whatever context is current: with several envs in one process, this env's context
        # must be made current before each render and before close.
        context = self.sim._render_context_offscreen if self.options.renders else None
        if context is not None:
            context.gl_ctx.make_current()

    def _reapply_render_flags(self) -> None:
        # A hard reset creates a new render context, so the flag is set after every reset.
        if self.options.renders and not self.options.reflection:
            import mujoco

            context = self.sim._render_context_offscreen
            if context is not None:
                context.scn.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0

    # -- state ---------------------------------------------------------------------------------

    def sim_state(self) -> np.ndarray:
        """The flattened MuJoCo state (time, qpos, qvel), the layout of LIBERO's init states."""
        return self._env.get_sim_state()

    def set_sim_state(self, state: np.ndarray) -> None:
        """Restore a flattened state recorded from this scene (e.g. to replay a demonstration)."""
        self._raw_obs = self._env.set_init_state(np.asarray(state, dtype=np.float64))
        self._forget_solver_history()
        self._captured = {}
        self._restart_goal()

    def state_hash(self) -> str:
        """SHA-256 over the flattened state and the fixture placements (model body poses)."""
        digest = hashlib.sha256()
        digest.update(np.ascontiguousarray(self.sim_state(), dtype=np.float64).tobytes())
        model = self.sim.model
        digest.update(np.ascontiguousarray(model.body_pos, dtype=np.float64).tobytes())
        digest.update(np.ascontiguousarray(model.body_quat, dtype=np.float64).tobytes())
        return digest.hexdigest()
