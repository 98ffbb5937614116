"""Recording one oracle attempt from a sampled start, and replaying recorded states (privileged state, frames)."""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np

from langgap.catalog.catalog import Catalog
from langgap.catalog.task import Task
from langgap.engine.context import task_context
from langgap.engine.rollout import run_episode
from langgap.errors import SimulationError
from langgap.policies.base import Policy, as_action_chunk
from langgap.sim.env import TaskEnv, state_from_robosuite
from langgap.sim.privileged import privileged_state

# The dynamic part of the privileged state that demonstrations keep (what `small-bc` observes).
PRIVILEGED_PREFIXES = ("body/", "joint/")
PRIVILEGED_KEYS = ("eef_pos", "eef_mat", "gripper_qpos")
# A sampled start closer than this (max-abs qpos) to a fixed init state counts as that init state.
SAME_STATE_TOLERANCE = 1e-6


@dataclass
class Demo:
    """One successful demonstration: row t holds the state before action t."""

    task_id: str
    instruction: str
    seed: int
    states: np.ndarray  # (T, D) flattened sim states
    actions: np.ndarray  # (T, 7) the actions executed (what a replay applies)
    labels: np.ndarray  # (T, 7) the demonstrator's commands (= actions without execution noise): training targets
    robot_states: np.ndarray  # (T, 8) LangGap/LeRobot 8-D state
    nearest_init_distance: float
    scene_hash: str  # the fixture placements of the seed's scene (see `scene_hash`)
    body_pos: np.ndarray  # (nbody, 3) model body placements (fixtures are placed in the model, not the state)
    body_quat: np.ndarray  # (nbody, 4)
    privileged: dict[str, np.ndarray] = field(default_factory=dict)  # key -> (T, ...)

    @property
    def length(self) -> int:
        return len(self.actions)


def scene_hash(env: TaskEnv) -> str:
    """SHA-256 of the model's body placements: the part of a scene a flattened sim state does not hold."""
    digest = hashlib.sha256()
    digest.update(np.ascontiguousarray(env.sim.model.body_pos, dtype=np.float64).tobytes())
    digest.update(np.ascontiguousarray(env.sim.model.body_quat, dtype=np.float64).tobytes())
    return digest.hexdigest()


def privileged_subset(env: TaskEnv) -> dict[str, np.ndarray]:
    """The privileged keys a demonstration keeps, at the env's current state."""
    full = privileged_state(env)
    return {k: v for k, v in full.items() if k in PRIVILEGED_KEYS or k.startswith(PRIVILEGED_PREFIXES)}


class ExecutionNoise:
    """Wraps a demonstrator: the environment receives its commands plus Gaussian noise on the six motion
    components (seeded per episode), while its clean commands are kept as the labels (DART): the data
    then covers the states a learner drifts into, each labelled with the correction."""

    def __init__(self, policy: Policy, noise: float):
        self.policy = policy
        self.spec = policy.spec
        self.noise = noise
        self.labels: list[np.ndarray] = []  # clean commands not yet executed, in execution order
        self._rng = np.random.default_rng(0)

    def reset(self, context) -> None:
        self.policy.reset(context.for_policy(self.spec))
        self.labels = []
        self._rng = np.random.default_rng([context.seed, 0xDA27])

    def act(self, observation) -> np.ndarray:
        clean = as_action_chunk(self.policy.act(observation), self.spec)
        self.labels = list(clean[: self.spec.replan])
        noisy = clean.copy()
        if self.noise > 0:
            noisy[:, :6] = np.clip(noisy[:, :6] + self._rng.normal(0.0, self.noise, (len(noisy), 6)), -1.0, 1.0)
        return noisy


def record_attempt(
    env: TaskEnv, policy: Policy, task: Task, catalog: Catalog, *, seed: int, style: str, noise: float = 0.0
) -> tuple[bool, Demo]:
    """Run `policy` once on `task` from the placement sampled with `seed` (with execution noise `noise`, see
    `ExecutionNoise`); returns (success, recording)."""
    states: list[np.ndarray] = []
    robot: list[np.ndarray] = []
    actions: list[np.ndarray] = []
    labels: list[np.ndarray] = []
    start: dict = {}
    demonstrator = ExecutionNoise(policy, noise)

    def on_start(e: TaskEnv) -> None:
        start["distance"] = e.nearest_init_distance()
        start["scene"] = scene_hash(e)
        start["body_pos"] = e.sim.model.body_pos.copy()
        start["body_quat"] = e.sim.model.body_quat.copy()
        states.append(e.sim_state().copy())
        robot.append(state_from_robosuite(e.robosuite_observation))

    def on_step(e: TaskEnv, _step: int, action: np.ndarray) -> None:
        actions.append(np.asarray(action, dtype=np.float64).copy())
        labels.append(demonstrator.labels.pop(0))
        states.append(e.sim_state().copy())
        robot.append(state_from_robosuite(e.robosuite_observation))

    # init_index 0 only names the attempt for the policy's own RNG; the start is the sampled placement.
    context = task_context(task, catalog, init_index=0, seed=seed, style=style)
    result = run_episode(env, demonstrator, context, on_step=on_step, on_start=on_start, sampled_start=True)
    if start["distance"] < SAME_STATE_TOLERANCE:
        raise SimulationError(f"{task.id}: the start sampled with seed {seed} is one of the fixed init states")
    # The last recorded state follows the last action; a demonstration keeps pre-action states only.
    demo = Demo(
        task_id=task.id,
        instruction=context.instruction,
        seed=seed,
        states=np.array(states[:-1]),
        actions=np.array(actions).reshape(-1, 7),
        labels=np.array(labels).reshape(-1, 7),
        robot_states=np.array(robot[:-1], dtype=np.float32),
        nearest_init_distance=start["distance"],
        scene_hash=start["scene"],
        body_pos=start["body_pos"],
        body_quat=start["body_quat"],
    )
    return result.success, demo


def start_episode(env: TaskEnv, demo: Demo) -> None:
    """Put `env` in the demonstration's first state: its scene and its recorded first state.

    A soft reset is enough: the recorded body placements (fixtures are placed in the model, and in some
    scenes, e.g. libero_spatial task 4 whose cabinet starts open, LIBERO's placement on a rebuilt model
    does not follow from the seed alone) are written into the model, then the recorded state.
    """
    env.reset(0, render=False)  # the recorded state replaces this one before anything is shown
    model = env.sim.model
    if model.body_pos.shape != demo.body_pos.shape:
        raise SimulationError(f"{demo.task_id}: the demonstration was recorded in another scene")
    model.body_pos[:] = demo.body_pos
    model.body_quat[:] = demo.body_quat
    # Settling leaves the controller as it was when the demonstration started (gripper command
    # saturated open); the recorded first state then replaces the settled one.
    env.settle()
    env.set_sim_state(demo.states[0])
    if scene_hash(env) != demo.scene_hash:
        raise SimulationError(f"{demo.task_id}: cannot rebuild the scene of the demonstration with seed {demo.seed}")


def replay_states(env: TaskEnv, demo: Demo, read: Callable[[TaskEnv], object]) -> Iterator[object]:
    """`read(env)` at each recorded state of `demo`, in the scene (fixtures included) of its seed."""
    start_episode(env, demo)
    for state in demo.states:
        env.set_sim_state(state)
        yield read(env)


def add_privileged(env: TaskEnv, demo: Demo) -> None:
    """Fill `demo.privileged` by replaying its states."""
    rows = list(replay_states(env, demo, privileged_subset))
    demo.privileged = {key: np.stack([row[key] for row in rows]) for key in rows[0]}
