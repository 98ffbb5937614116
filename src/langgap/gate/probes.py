"""The gate's probes of scenes, as work items for the engine's scheduler (any backend, its retries):

* `SettleProbe`: how far any object still moves over idle steps after the settle steps (a scene that
  does not come to rest fails the gate's "scene settles" check);
* `StartProbe`: every task's start from its own BDDL file (no policy runs), for the claims about starts.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from langgap.catalog.task import Task
from langgap.engine.execute import execute
from langgap.engine.runner import RunnerSetup
from langgap.engine.spec import ExecutionOptions
from langgap.engine.work import Job, JobHost
from langgap.gate.claims import Start
from langgap.stack import DEFAULT_STEPPING

SETTLE_INITS = 2
SETTLE_IDLE_STEPS = 20


@dataclass(frozen=True)
class SettleProbe(Job):
    """Largest displacement (m) of any object over idle steps after the settle steps, on the first `inits`
    init states of `task_id`'s scene (a fresh simulator of the task's own)."""

    kind: ClassVar[str] = "settle probe"

    task_id: str
    inits: int = SETTLE_INITS

    def perform(self, runner: JobHost) -> tuple[str, float]:
        """The task's id and its scene's drift."""
        from langgap.sim.env import TaskEnv

        worst = 0.0
        with TaskEnv(runner.catalog.get(self.task_id)) as env:
            bodies = [env.sim.model.body_name2id(o.root_body) for o in env.robosuite_env.objects_dict.values()]
            for index in range(min(self.inits, len(env.init_states))):
                env.reset(index)
                env.settle()
                before = env.sim.data.body_xpos[bodies].copy()
                env.settle(SETTLE_IDLE_STEPS)
                after = env.sim.data.body_xpos[bodies]
                worst = max(worst, float(np.linalg.norm(after - before, axis=1).max()))
        return self.task_id, worst


@dataclass(frozen=True)
class StartProbe(Job):
    """How `task_id` starts from init states 0..`inits`-1, built from its own BDDL file (no policy runs).

    Each task gets a simulator of its own, never a sibling's switched over (as the engine's workers do
    for episodes), since the claim is that each task's own BDDL file yields its source's state."""

    kind: ClassVar[str] = "start probe"

    task_id: str
    inits: int
    stepping: str = DEFAULT_STEPPING

    def perform(self, runner: JobHost) -> list[Start]:
        from langgap.engine.episode import scene_goals
        from langgap.engine.plan import episode_seed
        from langgap.sim.env import EnvOptions, TaskEnv

        task = runner.catalog.get(self.task_id)
        goals = scene_goals(task, runner.catalog)
        starts = []
        with TaskEnv(task, EnvOptions(stepping=self.stepping)) as env:
            for index in range(min(self.inits, len(env.init_states))):
                env.reset(index, seed=episode_seed(0, index))
                t0 = env.t0_hash or ""
                env.settle()
                holding = tuple(name for name, goal in goals.items() if env.goal_holds(goal))
                starts.append(Start(task.id, task.source, index, t0, holding))
        return starts


def settle_drifts(catalog: str, tasks: list[Task], options: ExecutionOptions) -> dict[tuple[str, str], float]:
    """The drift of every scene of `tasks` (suite, scene task) -> metres, probed on its first task."""
    first: dict[tuple[str, str], str] = {}
    for task in tasks:
        first.setdefault((task.suite, task.scene_task), task.id)
    scene_of = {task_id: scene for scene, task_id in first.items()}
    probes = [SettleProbe(task_id) for task_id in first.values()]
    found = execute(probes, RunnerSetup(catalog=catalog), options, unit="scene")
    return {scene_of[task_id]: drift for task_id, drift in found}


def scene_starts(
    catalog: str, tasks: list[Task], inits: int, options: ExecutionOptions, stepping: str = DEFAULT_STEPPING
) -> list[Start]:
    """Every task's start from init states 0..`inits`-1 (`StartProbe`), in the order of `tasks`."""
    probes = [StartProbe(task.id, inits, stepping) for task in tasks]
    setup = RunnerSetup(catalog=catalog, stepping=stepping)
    by_task = {starts[0].task_id: starts for starts in execute(probes, setup, options, unit="task") if starts}
    return [start for task in tasks for start in by_task.get(task.id, [])]
