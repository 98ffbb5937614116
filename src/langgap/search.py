"""A bounded search for a demonstration, where the oracle fails a task on an init state.

The oracle failing shows only that the oracle fails. Before a task is recorded as *unproven*, the
gate tries other episodes from the same plan entry (init state, seed, stepping): variations of the
oracle's own closed-loop plan, so every candidate starts from what the oracle already gets right.

* Contact primitives for what moves a drawer: the drawer opened by a grasp of its handle, or by a
  pressed drag with the hand's tilt (0-60 degrees down), its turn about the vertical (+-40 degrees)
  and how hard it presses (a target 5-50 mm below the bar) drawn at random; the approach, the contact
  and the pull follow from those (`policies.oracle.drawers`).
* Waypoints: Gaussian noise on every motion command (a standard deviation drawn up to
  `MAX_NOISE`, each candidate its own draw), which moves every waypoint the plan reaches.

Each candidate is one episode; the first that reaches the goal is kept as a `Demonstration`, which the
gate stores, replays from the file and verifies before it counts (`langgap.validate`). The search is
seeded: the same task, init state and budget try the same candidates.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from langgap.catalog.catalog import Catalog
from langgap.catalog.task import Task
from langgap.demos.searched import Demonstration, demonstration_path, replay_env, verify
from langgap.engine.context import task_context
from langgap.engine.rollout import env_options_for, run_episode
from langgap.goals import atoms
from langgap.policies import make_policy
from langgap.policies.oracle.planner import order_goal
from langgap.policies.oracle.scene import Scene
from langgap.sim.env import TaskEnv
from langgap.stack import physics_stack
from langgap.version import code_version

BUDGET = 16  # candidate episodes per init state the oracle fails
MAX_NOISE = 0.15  # action units
TILT_DEG = (0.0, 60.0)
TURN_DEG = (-40.0, 40.0)
PRESS_DEPTH_M = (0.005, 0.05)


@dataclass(frozen=True)
class Candidate:
    """One episode to try: the oracle with these arguments (`--policy-arg` strings)."""

    policy_args: dict[str, str]

    def __str__(self) -> str:
        return "oracle " + " ".join(f"{k}={v}" for k, v in sorted(self.policy_args.items()))


@dataclass
class SearchResult:
    """What a search tried on one init state, and the demonstration it found (None: none)."""

    task_id: str
    init_index: int
    tried: list[tuple[Candidate, bool, int]] = field(default_factory=list)  # candidate, success, steps
    found: Demonstration | None = None

    @property
    def hits(self) -> int:
        return sum(success for _, success, _ in self.tried)


def candidates(moves_drawer: bool, budget: int, rng: np.random.Generator) -> list[Candidate]:
    """`budget` variations of the oracle's plan: where the goal moves a drawer, every other one draws its
    contact primitive (grasp, or a pressed drag with random tilt, turn and depth); every one draws its
    action noise."""
    found = []
    for k in range(budget):
        args = {"noise": f"{rng.uniform(0.0, MAX_NOISE):.3f}", "noise_seed": str(k + 1)}
        if moves_drawer and k % 2 == 0:
            if rng.random() < 0.5:
                args["drawer"] = "grasp"
            else:
                tilt, turn, depth = rng.uniform(*TILT_DEG), rng.uniform(*TURN_DEG), rng.uniform(*PRESS_DEPTH_M)
                args["drawer"] = f"press:{tilt:.1f}:{turn:.1f}:{depth:.3f}"
        found.append(Candidate(args))
    return found


def moves_a_drawer(scene: Scene, task: Task) -> bool:
    """Whether meeting the task's goal opens or closes a sliding part (drawers the goal puts things in included)."""
    steps = order_goal(scene, tuple(atoms(task.goal)))
    return any(
        p.name in ("Open", "Close") and p.args[0] in scene.articulated and scene.articulation(p.args[0]).slide
        for p in steps
    )


def search(
    task: Task,
    catalog: Catalog,
    *,
    init_index: int,
    seed: int,
    stepping: str,
    budget: int = BUDGET,
    search_seed: int = 0,
    stop_at_first: bool = True,
    oracle_args: dict[str, str] | None = None,
) -> SearchResult:
    """Try up to `budget` candidates on the plan entry (init state, seed); keep the first that does the task
    (all of them are tried when not `stop_at_first`, to measure a hit rate). `oracle_args` configure the
    oracle whose plan the candidates vary (what a candidate draws replaces them)."""
    rng = np.random.default_rng([search_seed, init_index, seed])
    result = SearchResult(task.id, init_index)
    context = task_context(task, catalog, init_index=init_index, seed=seed)
    probe = make_policy("oracle", oracle_args)
    with TaskEnv(task, env_options_for(probe, stepping=stepping)) as env:
        scene = Scene(env.reset(init_index, seed=seed, render=False).privileged)
        for candidate in candidates(moves_a_drawer(scene, task), budget, rng):
            policy = make_policy("oracle", (oracle_args or {}) | candidate.policy_args)
            actions: list[np.ndarray] = []

            def keep(_env: TaskEnv, _step: int, action: np.ndarray, kept: list = actions) -> None:
                kept.append(action.copy())

            outcome = run_episode(env, policy, context, on_step=keep)
            result.tried.append((candidate, outcome.success, outcome.steps))
            if outcome.success and result.found is None:
                result.found = Demonstration(
                    task_id=task.id,
                    catalog=catalog.name,
                    init_index=init_index,
                    seed=seed,
                    stepping=stepping,
                    steps=outcome.steps,
                    instruction=context.instruction,
                    found_by=str(Candidate((oracle_args or {}) | candidate.policy_args)),
                    made_with={"code_version": code_version(), "physics": physics_stack(stepping)},
                    actions=np.array(actions),
                )
                if stop_at_first:
                    break
    return result


def demonstrate(
    catalog: Catalog,
    failures: dict[str, list[tuple[int, int]]],
    directory: Path,
    *,
    stepping: str,
    budget: int = BUDGET,
    oracle_args: dict[str, str] | None = None,
) -> dict[str, list[int]]:
    """Search a demonstration for each (init state, seed) of `failures` (task id -> the plan entries the
    oracle failed, in order); each one found is stored in `directory`/<task id>/, read back, replayed on
    a fresh environment and kept only if it does the task at its recorded step. A task's search stops at
    its first init state without one (which bounds a task no candidate does to one budget). Returns task
    id -> the init states now shown doable."""
    shown: dict[str, list[int]] = {}
    for task_id, entries in failures.items():
        task = catalog.get(task_id)
        for init_index, seed in entries:
            entry = dict(init_index=init_index, seed=seed, stepping=stepping, budget=budget, oracle_args=oracle_args)
            found = search(task, catalog, **entry).found
            if found is None:
                break  # the task stays short of a demonstration there: its other init states would not decide it
            stored = Demonstration.load(found.save(demonstration_path(directory / task_id, init_index)))
            with replay_env(task, stepping) as env:
                verify(env, stored, catalog)
            shown.setdefault(task_id, []).append(init_index)
    return shown
