"""Which goals a collection's demonstrations pass through, state by state.

A split holds a task out by its sentence; a collection can still show its outcome. Pushing the plate to the
front of the stove can leave the cream cheese there too, so a policy trained on that demonstration has seen
the cream cheese in front of the stove, though no sentence asked for it. `goals_reached` finds such states by
setting every recorded state in turn (no physics, no rendering), and the state after the last action by an
open-loop replay of the actions, and judging the given tasks' goals at each.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path

from langgap.catalog.catalog import load_catalog
from langgap.catalog.task import Task
from langgap.demos.compact import demo_files, load_demo, read_manifest
from langgap.demos.record import replay_states
from langgap.demos.verify import replay_demo
from langgap.sim.env import TaskEnv


@dataclass(frozen=True)
class DemoReach:
    """One demonstration, as `goals_reached` judged it.

    Attributes:
        task_id: The task it demonstrates.
        scene: The key of its scene.
        reached: The ids of the looked-for goals it passes through.
        replayed: Whether it was replayed (only one set in a looked-for task's scene is).
        last_judged: Whether the state after its last action was judged (its replay reached its goal there).
    """

    task_id: str
    scene: str
    reached: frozenset[str] = frozenset()
    replayed: bool = False
    last_judged: bool = False


@dataclass(frozen=True)
class CollectionReach:
    """What `goals_reached` found in one collection: each demonstration, and the scene of each task looked for
    (id -> scene key). `among` narrows it to some of those tasks (a split's held-out ones)."""

    demos: tuple[DemoReach, ...]
    looked_for: dict[str, str]

    def among(self, task_ids: Sequence[str]) -> CollectionReach:
        """The same collection, judged for `task_ids` only (ids of tasks looked for)."""
        keep = set(task_ids)
        scenes = {self.looked_for[i] for i in keep}
        return CollectionReach(
            tuple(
                replace(d, reached=d.reached & keep, replayed=d.replayed and d.scene in scenes,
                        last_judged=d.last_judged and d.scene in scenes)
                for d in self.demos
            ),
            {i: self.looked_for[i] for i in keep},
        )  # fmt: skip

    @property
    def demonstrations(self) -> Counter[str]:
        """How many demonstrations of each task the collection holds (task id -> count)."""
        return Counter(d.task_id for d in self.demos)

    @property
    def total(self) -> int:
        """How many demonstrations the collection holds."""
        return len(self.demos)

    @property
    def replayed(self) -> int:
        """How many were replayed: those set in the scene of a task looked for."""
        return sum(d.replayed for d in self.demos)

    @property
    def last_unknown(self) -> int:
        """How many replayed ones did not replay to their goal on this physics stack, so the state after their
        last action (which a demonstration does not store) was not judged."""
        return sum(d.replayed and not d.last_judged for d in self.demos)

    @property
    def reached(self) -> dict[str, Counter[str]]:
        """For each goal reached (its task's id), how many demonstrations of each task reached it."""
        out: dict[str, Counter[str]] = {}
        for demo in self.demos:
            for goal_id in demo.reached:
                out.setdefault(goal_id, Counter())[demo.task_id] += 1
        return out


def goals_reached(root: str | Path, tasks: Sequence[Task]) -> CollectionReach:
    """Replay every demonstration of the collection at `root` and find which goals of `tasks` it passes through.

    A goal counts where it holds at a recorded state, or after the last action (an open-loop replay of the
    actions, where it reaches the demonstration's goal at its last step), but not at the demonstration's first
    (an episode's goals are counted so too: `SceneWatch`), order ignored. Only the tasks set in a
    demonstration's own scene (same scene key) are judged on it; a task's own demonstrations count like any
    other. Each demonstration is replayed once, however many tasks are looked for.

    Args:
        root: A collection (`langgap collect`'s output directory).
        tasks: The tasks whose goals to look for, from any catalog.

    Raises:
        DemoFileError: `root` is not a collection or a file of it cannot be read.
    """
    catalog = load_catalog(read_manifest(Path(root))["catalog"])
    looked_for = {task.id: catalog.scene_key(task) for task in tasks}
    by_scene: dict[str, list[Task]] = {}
    for task in tasks:
        by_scene.setdefault(looked_for[task.id], []).append(task)
    demos: list[DemoReach] = []
    env: TaskEnv | None = None
    try:
        for path in demo_files(Path(root)):
            demo = load_demo(path)
            own = catalog.get(demo.task_id)
            scene = catalog.scene_key(own)
            watched = by_scene.get(scene, [])
            if not watched:
                demos.append(DemoReach(own.id, scene))
                continue
            if env is None or env.task.id != own.id:
                if env is not None:
                    env.close()
                env = TaskEnv(own)
            # A demonstration stores the states before its actions; the one after its last comes from replaying
            # its actions, and only a replay that reaches its goal at its last step (`replay_demo`) reproduces it.
            last = [_holding(env, watched)] if replay_demo(env, demo).ok else []
            held = list(replay_states(env, demo, partial(_holding, tasks=watched))) + last
            reached = frozenset(set().union(*held[1:]) - held[0])
            demos.append(DemoReach(own.id, scene, reached, replayed=True, last_judged=bool(last)))
    finally:
        if env is not None:
            env.close()
    return CollectionReach(tuple(demos), looked_for)


def _holding(env: TaskEnv, tasks: list[Task]) -> set[str]:
    return {t.id for t in tasks if env.goal_holds(t.goal)}
