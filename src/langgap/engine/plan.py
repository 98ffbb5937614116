"""The episode plan: every (task, init index, seed, condition) of a run, fixed before anything runs.

Nothing in the plan depends on how an earlier episode ended, so a run can be split over workers,
killed and resumed, and still consist of exactly the same episodes.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import ClassVar

from langgap.catalog.catalog import Catalog
from langgap.catalog.task import Task
from langgap.errors import CatalogError, InitStateError
from langgap.records import EpisodeKey

CONDITIONS = ("given", "empty", "shuffled", "source")
CONDITION_HELP = (
    "given: the task's instruction; empty: an empty string; shuffled: the instruction of another task on the "
    "same scene; source: the instruction of the task's source (original) task"
)


@dataclass(frozen=True)
class PlannedEpisode:
    """An evaluation episode: the first kind of work item (`langgap.engine.work.WorkItem`)."""

    kind: ClassVar[str] = "episode"
    size: ClassVar[int] = 1  # one episode's timeout

    key: EpisodeKey
    instruction: str  # the exact string the policy will receive
    scene: str = ""  # the scene it is set in: a worker's environment serves every task of one scene
    film: bool = False  # record a clip of the episode (the run's `--video` chose it)

    @property
    def task_id(self) -> str:
        return self.key.task_id

    @property
    def instruction_sha256(self) -> str:
        return hashlib.sha256(self.instruction.encode("utf-8")).hexdigest()


# Repeat r of a run uses run seed + r * REPEAT_STRIDE: above any init index, so seeds never collide.
REPEAT_STRIDE = 1000


def episode_seed(run_seed: int, init_index: int, repeat: int = 0) -> int:
    """The env seed of an episode. It depends on the init index (and the repeat) only, not the task, so
    sibling tasks start from the identical scene: same init state and same fixture placement."""
    return run_seed + repeat * REPEAT_STRIDE + init_index


def repeat_of(seed: int, init_index: int, run_seed: int) -> int:
    """Which repeat an episode's seed belongs to (the inverse of `episode_seed`)."""
    return (seed - init_index - run_seed) // REPEAT_STRIDE


def condition_instruction(task: Task, catalog: Catalog, condition: str, style: str, init_index: int) -> str:
    """The instruction a policy receives for `task` under a language `condition`."""
    if condition == "given":
        return task.instruction(style)
    if condition == "empty":
        return ""
    if condition == "source":
        return catalog.get(task.source).instruction(style)
    if condition == "shuffled":
        own = task.instruction(style)
        pool = [t for t in catalog.scene_mates(task) if t.id != task.id and t.instruction(style) != own]
        if not pool:  # a scene with one task (e.g. libero_10): fall back to the suite
            pool = [t for t in catalog if t.suite == task.suite and t.instruction(style) != own]
        if not pool:
            raise CatalogError(f"no other instruction to shuffle in for {task.id}")
        # Deterministic and spread over the pool: the choice depends on the task and the init index only.
        digest = hashlib.sha256(f"{task.id}#{init_index}".encode()).digest()
        return pool[int.from_bytes(digest[:8], "big") % len(pool)].instruction(style)
    raise CatalogError(f"unknown condition {condition!r} ({CONDITION_HELP})")


def build_plan(
    tasks: list[Task],
    catalog: Catalog,
    *,
    episodes: int,
    seed: int = 0,
    conditions: tuple[str, ...] = ("given",),
    style: str = "libero",
    first_init: int = 0,
    repeats: int = 1,
) -> list[PlannedEpisode]:
    """Episodes `first_init .. first_init+episodes-1` (init state k = episode k) of every task × condition,
    each `repeats` times with its own seed (same init state)."""
    if episodes < 1:
        raise CatalogError(f"--episodes must be at least 1, got {episodes}")
    unknown = [c for c in conditions if c not in CONDITIONS]
    if unknown:
        raise CatalogError(f"unknown condition(s) {unknown} ({CONDITION_HELP})")
    from langgap.catalog import files
    from langgap.catalog.files import scene_key

    plan = []
    for task in tasks:
        available = files.init_states(task).shape[0]
        if first_init < 0 or first_init + episodes > available:
            raise InitStateError(
                f"{task.id} has {available} init states; init indices {first_init}..{first_init + episodes - 1} "
                "are out of range"
            )
        for condition in conditions:
            for init_index in range(first_init, first_init + episodes):
                instruction = condition_instruction(task, catalog, condition, style, init_index)
                for repeat in range(repeats):
                    key = EpisodeKey(task.id, init_index, episode_seed(seed, init_index, repeat), condition)
                    plan.append(PlannedEpisode(key, instruction, scene=scene_key(task)))
    return plan
