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
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from langgap.catalog.catalog import load_catalog
from langgap.catalog.task import Task
from langgap.demos.compact import demo_files, load_demo, read_manifest
from langgap.demos.record import replay_states
from langgap.demos.verify import replay_demo
from langgap.sim.env import TaskEnv


@dataclass(frozen=True)
class CollectionReach:
    """What `goals_reached` found in one collection.

    Attributes:
        demonstrations: How many demonstrations of each task the collection holds (task id -> count).
        replayed: How many of them are set in the scene of a task looked for, and so were replayed.
        last_unknown: How many of those did not replay to their goal on this physics stack, so the state
            after their last action (which a demonstration does not store) was not judged.
        reached: For each goal reached (its task's id), how many demonstrations of each task reached it.
    """

    demonstrations: Counter[str] = field(default_factory=Counter)
    replayed: int = 0
    last_unknown: int = 0
    reached: dict[str, Counter[str]] = field(default_factory=dict)

    @property
    def total(self) -> int:
        """How many demonstrations the collection holds."""
        return sum(self.demonstrations.values())


def goals_reached(root: str | Path, tasks: Sequence[Task]) -> CollectionReach:
    """Replay every demonstration of the collection at `root` and find which goals of `tasks` it passes through.

    A goal counts where it holds at a recorded state, or after the last action (an open-loop replay of the
    actions, where it reaches the demonstration's goal at its last step), but not at the demonstration's first
    (an episode's goals are counted so too: `SceneWatch`), order ignored. Only the tasks set in a
    demonstration's own scene (same scene key) are judged on it; a task's own demonstrations count like any
    other.

    Args:
        root: A collection (`langgap collect`'s output directory).
        tasks: The tasks whose goals to look for, from any catalog.

    Raises:
        DemoFileError: `root` is not a collection or a file of it cannot be read.
    """
    catalog = load_catalog(read_manifest(Path(root))["catalog"])
    by_scene: dict[str, list[Task]] = {}
    for task in tasks:
        by_scene.setdefault(catalog.scene_key(task), []).append(task)
    seen: Counter[str] = Counter()
    replayed = 0
    last_unknown = 0
    reached: dict[str, Counter[str]] = {}
    env: TaskEnv | None = None
    try:
        for path in demo_files(Path(root)):
            demo = load_demo(path)
            own = catalog.get(demo.task_id)
            seen[own.id] += 1
            watched = by_scene.get(catalog.scene_key(own), [])
            if not watched:
                continue
            replayed += 1
            if env is None or env.task.id != own.id:
                if env is not None:
                    env.close()
                env = TaskEnv(own)
            # A demonstration stores the states before its actions; the one after its last comes from replaying
            # its actions, and only a replay that reaches its goal at its last step (`replay_demo`) reproduces it.
            last = [_holding(env, watched)] if replay_demo(env, demo).ok else []
            last_unknown += not last
            held = list(replay_states(env, demo, partial(_holding, tasks=watched))) + last
            for goal_id in set().union(*held[1:]) - held[0]:
                reached.setdefault(goal_id, Counter())[own.id] += 1
    finally:
        if env is not None:
            env.close()
    return CollectionReach(seen, replayed, last_unknown, reached)


def _holding(env: TaskEnv, tasks: list[Task]) -> set[str]:
    return {t.id for t in tasks if env.goal_holds(t.goal)}
