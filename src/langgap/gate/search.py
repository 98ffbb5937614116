"""A bounded search for a demonstration, where the oracle fails a task on an init state.

The oracle failing shows only that the oracle fails. Before a task is recorded as *unproven*, the
gate tries other episodes from the same plan entry (init state, seed, stepping): variations of the
oracle's own closed-loop plan, so every candidate starts from what the oracle already gets right.

* Contact primitives for what moves a drawer: the drawer opened by a grasp of its handle, or by a
  pressed drag with the hand's tilt (0-60 degrees down), its turn about the vertical (+-40 degrees)
  and how hard it presses (a target 5-50 mm below the bar); the approach, the contact and the pull
  follow from those (`policies.oracle.drawers`, `drawer_press`). The first candidates draw them over
  those whole ranges; later ones around the pressed drag that took the drawer furthest toward its goal
  (`Sampler`: a cross-entropy search on how far the drawer moved).
* Waypoints: Gaussian noise on every motion command (each candidate its own draw and size), which
  moves every waypoint the plan reaches.

Each candidate is one episode; the first that reaches the goal is kept as a `Demonstration`, which is
stored, replayed from the file and verified before the gate (`langgap.gate`) counts it. A task's search
is one work item for the engine's scheduler (`SearchTask`). The search is seeded: the same task, init
state and budget try the same candidates.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import ClassVar

import numpy as np

from langgap.catalog.catalog import Catalog
from langgap.catalog.task import Task
from langgap.engine.context import task_context
from langgap.engine.execute import execute
from langgap.engine.rollout import env_options_for, run_episode
from langgap.engine.runner import RunnerSetup
from langgap.engine.spec import ExecutionOptions
from langgap.engine.work import Job, JobHost
from langgap.gate.demonstrations import (
    Demonstration,
    DemonstrationError,
    demonstration_path,
    replay,
    replay_env,
    save_verified,
)
from langgap.goals import atoms
from langgap.policies import make_policy
from langgap.policies.oracle.planner import order_goal
from langgap.policies.oracle.scene import Scene
from langgap.sim.env import TaskEnv
from langgap.stack import physics_stack
from langgap.version import code_version

BUDGET = 16  # candidate episodes per init state the oracle fails
MAX_NOISE = 0.15  # action units
PRIMITIVE_NOISE = 0.05
EXPLORE = 6  # candidates drawn over the primitives' whole ranges before the search centres on the best
GRASP_SHARE = 0.25  # of those, the share that grasp the handle instead of pressing it
SPREAD = (10.0, 10.0, 0.008)  # tilt, turn (degrees), depth (metres) around the best so far
SHRINK = 0.85  # the spread's factor per candidate after the first `EXPLORE`
TILT_DEG = (0.0, 60.0)
TURN_DEG = (-40.0, 40.0)
PRESS_DEPTH_M = (0.005, 0.05)


@dataclass(frozen=True)
class Candidate:
    """One episode to try: the oracle with these arguments (`--policy-arg` strings)."""

    policy_args: dict[str, str]

    def __str__(self) -> str:
        return "oracle " + " ".join(f"{k}={v}" for k, v in sorted(self.policy_args.items()))

    @staticmethod
    def parse(found_by: str) -> Candidate:
        """The candidate a demonstration's `found_by` names (what `str` wrote)."""
        name, *args = found_by.split()
        pairs = [arg.partition("=") for arg in args]
        if name != "oracle" or not all(sep for _, sep, _ in pairs):
            raise DemonstrationError(f"found by {found_by!r}: not an oracle with key=value arguments")
        return Candidate({key: value for key, _, value in pairs})


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


@dataclass(frozen=True)
class Press:
    """A pressed drag's parameters: tilt and turn (degrees), press depth (metres)."""

    tilt: float
    turn: float
    depth: float

    def clipped(self) -> Press:
        return Press(float(np.clip(self.tilt, *TILT_DEG)), float(np.clip(self.turn, *TURN_DEG)),
                     float(np.clip(self.depth, *PRESS_DEPTH_M)))  # fmt: skip

    def __str__(self) -> str:
        return f"press:{self.tilt:.1f}:{self.turn:.1f}:{self.depth:.3f}"


class Sampler:
    """Draws the candidates one at a time, learning from how far each got (a cross-entropy search).

    Where the goal moves a drawer, every candidate draws its contact primitive: the first `EXPLORE`
    a grasp or a pressed drag with tilt, turn and depth drawn over their whole ranges; after them, the
    pressed drag that moved the drawer furthest toward its goal so far is the centre, and new ones are
    drawn around it, the spread shrinking each time. Every candidate draws its action noise (a small one
    with a primitive, up to `MAX_NOISE` without). Where no drawer moves, the noise is all there is.
    """

    def __init__(self, moves_drawer: bool, rng: np.random.Generator):
        self.moves_drawer = moves_drawer
        self.rng = rng
        self.best: tuple[float, Press] | None = None
        self.drawn = 0

    def draw(self) -> Candidate:
        rng, k = self.rng, self.drawn
        self.drawn += 1
        if not self.moves_drawer:
            return Candidate({"noise": f"{rng.uniform(0.0, MAX_NOISE):.3f}", "noise_seed": str(k + 1)})
        args = {"noise": f"{rng.uniform(0.0, PRIMITIVE_NOISE):.3f}", "noise_seed": str(k + 1)}
        if k < EXPLORE or self.best is None:
            if rng.random() < GRASP_SHARE:
                return Candidate(args | {"drawer": "grasp"})
            press = Press(rng.uniform(*TILT_DEG), rng.uniform(*TURN_DEG), rng.uniform(*PRESS_DEPTH_M))
        else:
            spread = SHRINK ** (k - EXPLORE)
            centre = self.best[1]
            press = Press(rng.normal(centre.tilt, SPREAD[0] * spread), rng.normal(centre.turn, SPREAD[1] * spread),
                          rng.normal(centre.depth, SPREAD[2] * spread)).clipped()  # fmt: skip
        return Candidate(args | {"drawer": str(press)})

    def tell(self, candidate: Candidate, progress: float) -> None:
        """How far `candidate` got (0: the drawer never moved toward its goal; 1: it got there)."""
        drawer = candidate.policy_args.get("drawer", "")
        if drawer.startswith("press:") and progress > 0 and (self.best is None or progress > self.best[0]):
            tilt, turn, depth = (float(x) for x in drawer.split(":")[1:])
            self.best = (progress, Press(tilt, turn, depth))


def _drawer_steps(scene: Scene, task: Task) -> list:
    """The sub-goals that open or close a sliding part (drawers the goal puts things in included)."""
    steps = order_goal(scene, tuple(atoms(task.goal)))
    return [p for p in steps if p.name in ("Open", "Close") and p.args[0] in scene.articulated
            and scene.articulation(p.args[0]).slide]  # fmt: skip


def drawer_progress(start: Scene, end: Scene, task: Task) -> float:
    """How far the sliding parts the goal moves went toward their goal states, the least of them (0..1)."""
    fractions = []
    for p in _drawer_steps(start, task):
        before, after = start.articulation(p.args[0]), end.articulation(p.args[0])
        goal = before.target("open" if p.name == "Open" else "close")
        way = goal - before.qpos
        fractions.append(float(np.clip((after.qpos - before.qpos) / way, 0.0, 1.0)) if abs(way) > 1e-9 else 1.0)
    return min(fractions, default=0.0)


def moves_a_drawer(scene: Scene, task: Task) -> bool:
    """Whether meeting the task's goal opens or closes a sliding part (drawers the goal puts things in included)."""
    return bool(_drawer_steps(scene, task))


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
    probe = make_policy("oracle", oracle_args)
    with TaskEnv(task, env_options_for(probe, stepping=stepping)) as env:
        start = Scene(env.reset(init_index, seed=seed, render=False).privileged)
        sampler = Sampler(moves_a_drawer(start, task), rng)
        for _ in range(budget):
            candidate = sampler.draw()
            steps, found = _play(env, Candidate((oracle_args or {}) | candidate.policy_args), catalog, init_index, seed)
            result.tried.append((candidate, found is not None, steps))
            sampler.tell(candidate, drawer_progress(start, Scene(env.observe(()).privileged), task))
            if found is not None and result.found is None:
                result.found = found
                if stop_at_first:
                    break
    return result


def _play(
    env: TaskEnv, candidate: Candidate, catalog: Catalog, init_index: int, seed: int
) -> tuple[int, Demonstration | None]:
    """One episode of `candidate` on the plan entry: the steps it ran, and its demonstration where it did the
    task (else None)."""
    context = task_context(env.task, catalog, init_index=init_index, seed=seed)
    actions: list[np.ndarray] = []

    def keep(_env: TaskEnv, _step: int, action: np.ndarray) -> None:
        actions.append(action.copy())

    outcome = run_episode(env, make_policy("oracle", candidate.policy_args), context, on_step=keep)
    if not outcome.success:
        return outcome.steps, None
    stepping = env.options.stepping
    return outcome.steps, Demonstration(
        task_id=env.task.id,
        catalog=catalog.name,
        init_index=init_index,
        seed=seed,
        stepping=stepping,
        steps=outcome.steps,
        instruction=context.instruction,
        found_by=str(candidate),
        made_with={"code_version": code_version(), "physics": physics_stack(stepping)},
        actions=np.array(actions),
    )  # fmt: skip


def remake(demo: Demonstration, catalog: Catalog) -> tuple[Demonstration, str] | None:
    """A demonstration of `demo`'s task and plan entry that replays on the installed physics stack, and how it was
    made, or None where neither way below does the task.

    A demonstration replays open loop, so it holds only on the stack it was recorded on; on another (another BLAS
    kernel: langgap/blas.py) its actions may reach the goal sooner, and they are kept up to there (`recorded
    actions`); otherwise the candidate that found it (its `found_by`), which acts closed loop, plays again
    (`finder`)."""
    task = catalog.get(demo.task_id)
    made_with = {"code_version": code_version(), "physics": physics_stack(demo.stepping)}
    with replay_env(task, demo.stepping) as env:
        try:
            replayed = replay(env, demo, catalog)
        except DemonstrationError:  # its actions ran out first
            replayed = None
    if replayed is not None and replayed.success and replayed.steps < demo.steps:
        kept = replace(demo, steps=replayed.steps, actions=demo.actions[: replayed.steps], made_with=made_with)
        return kept, "recorded actions"
    candidate = Candidate.parse(demo.found_by)
    with TaskEnv(task, env_options_for(make_policy("oracle", candidate.policy_args), stepping=demo.stepping)) as env:
        found = _play(env, candidate, catalog, demo.init_index, demo.seed)[1]
    return (found, "finder") if found is not None else None


@dataclass(frozen=True)
class SearchTask(Job):
    """The work item of one task's search: the plan entries (init state, seed) the oracle failed, in order.

    Each demonstration found is stored in the runner's output directory under the task's id, read back and
    replayed on a fresh environment; only one that does the task at its recorded step counts. One that does not
    fails the work item with the replay's error: a search is deterministic, so that is a fault to fix (the
    simulator or the file), never a candidate to pass over. The search
    stops at the task's first init state without one (which bounds a task no candidate does to one
    budget: its other init states would not decide it)."""

    kind: ClassVar[str] = "search"

    task_id: str
    entries: tuple[tuple[int, int], ...]
    stepping: str
    budget: int = BUDGET
    oracle_args: tuple[tuple[str, str], ...] = ()

    @property
    def size(self) -> int:
        return len(self.entries) * (self.budget + 1)  # the candidates, and each find's replay

    def perform(self, runner: JobHost) -> tuple[str, list[int]]:
        """The task's id, and the init states now shown doable."""
        catalog, task = runner.catalog, runner.catalog.get(self.task_id)
        shown = []
        for init_index, seed in self.entries:
            found = search(task, catalog, init_index=init_index, seed=seed, stepping=self.stepping,
                           budget=self.budget, oracle_args=dict(self.oracle_args) or None).found  # fmt: skip
            if found is None:
                break
            save_verified(found, demonstration_path(runner.output_dir / self.task_id, init_index), catalog)
            shown.append(init_index)
        return self.task_id, shown


def demonstrate(
    catalog: str,
    failures: dict[str, list[tuple[int, int]]],
    directory: Path,
    *,
    stepping: str,
    budget: int = BUDGET,
    oracle_args: dict[str, str] | None = None,
    options: ExecutionOptions | None = None,
) -> dict[str, list[int]]:
    """Search demonstrations for the (init state, seed) entries of `failures` (task id -> the plan entries
    the oracle failed, in order) of catalog `catalog` (a name or registry path), a task per work item
    (`SearchTask`) run as `options` say, each one found stored in `directory`/<task id>/. Returns task id
    -> the init states now shown doable."""
    args = tuple(sorted((oracle_args or {}).items()))
    items = [SearchTask(t, tuple(entries), stepping, budget, args) for t, entries in failures.items()]
    setup = RunnerSetup(catalog=catalog, run_dir=str(directory), stepping=stepping)
    found = execute(items, setup, options or ExecutionOptions(), unit="task", describe=lambda r: f"{r[0]}: {r[1]}")
    return {task_id: shown for task_id, shown in found if shown}
