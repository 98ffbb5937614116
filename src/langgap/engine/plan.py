"""The episode plan: every (task, init index, seed, condition) of a run, fixed before anything runs.

Nothing in the plan depends on how an earlier episode ended, so a run can be split over workers,
killed and resumed, and still consist of exactly the same episodes.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import ClassVar, TypeVar

import numpy as np

from langgap.catalog.catalog import Catalog
from langgap.catalog.task import Task
from langgap.errors import CatalogError, CatalogParameterError, InitStateError
from langgap.records import EpisodeKey
from langgap.vocabulary import SWITCH, Condition, TaskKind, switch_step

# What each condition sends the policy: `langgap eval --condition`'s help, and the error naming an unknown condition.
_CONDITION_MEANING = {
    Condition.GIVEN: "the task's instruction",
    Condition.EMPTY: "an empty string",
    Condition.SHUFFLED: "the instruction of another task on the same scene",
    Condition.SOURCE: f"the instruction of the task's source ({TaskKind.ORIGINAL}) task",
    Condition.NONSENSE: "as many words drawn from the catalog's vocabulary",
    f"{SWITCH}K": f"another task's instruction from the same scene (an {TaskKind.EXTENDED} task's source, an "
    f"{TaskKind.ORIGINAL}'s sibling) until policy step K, then the task's own",
}
CONDITION_HELP = "; ".join(f"{condition}: {meaning}" for condition, meaning in _CONDITION_MEANING.items())
T = TypeVar("T")


@dataclass(frozen=True)
class PlannedEpisode:
    """An evaluation episode: the first kind of work item (`langgap.engine.work.WorkItem`)."""

    kind: ClassVar[str] = "episode"
    size: ClassVar[int] = 1  # one episode's timeout

    key: EpisodeKey
    instruction: str  # the exact string the policy will receive first
    scene: str  # the key of the scene it is set in (a worker's environment serves every task of one), recorded
    # The tasks whose goals every step judges: every task set in its scene (`Catalog.scene_mates`), found once
    # per task by the plan rather than once per episode by the worker that runs it.
    watched: tuple[str, ...]
    film: bool = False  # record a clip of the episode (the run's `--video` chose it)
    # (policy step, instruction): where the instruction changes mid-episode (condition `switch:K`)
    changes: tuple[tuple[int, str], ...] = ()
    started_as: str = ""  # the task whose goal the first instruction asks for, when a change follows

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


def unknown_conditions(conditions: tuple[str, ...]) -> list[str]:
    """The conditions that are neither a fixed one (`Condition`) nor a valid `switch:K`."""
    return [c for c in conditions if c not in tuple(Condition) and switch_step(c) is None]


def unknown_conditions_text(unknown: list[str]) -> str:
    """The error naming conditions that are none (`unknown_conditions`): a `switch:` whose K is not a whole
    number of 1 or more says so, any other names every condition."""
    switches = [c for c in unknown if c.startswith(SWITCH)]
    others = [c for c in unknown if not c.startswith(SWITCH)]
    parts = [f"unknown condition(s) {others} ({CONDITION_HELP})"] if others or not switches else []
    if switches:
        parts.append(
            f"{', '.join(map(repr, switches))}: {SWITCH}K takes K, the policy step at which the instruction changes, "
            "as a whole number of 1 or more"
        )
    return "; ".join(parts)


def _pick(pool: Sequence[T], *salt) -> T:
    """A deterministic member of `pool`, spread over it by `salt` (a task id, an init index, a seed)."""
    digest = hashlib.sha256("#".join(str(s) for s in salt).encode()).digest()
    return pool[int.from_bytes(digest[:8], "big") % len(pool)]


@functools.lru_cache(maxsize=8)
def _vocabulary(catalog: Catalog, style: str) -> tuple[str, ...]:
    """The words of every instruction of `catalog` in `style`, sorted (once per catalog and style)."""
    return tuple(sorted({word for t in catalog for word in t.instruction(style).split()}))


class TaskLanguage:
    """What the episodes of `task` may be told under each language condition: its instruction, its source's, the
    other instructions of its scene, the tasks a `switch:K` may start under, words of the catalog. Each is read
    from `catalog` the first time a condition asks for it, so a plan asks the catalog once per task, not once per
    episode."""

    def __init__(self, task: Task, catalog: Catalog, style: str):
        self.task, self.catalog, self.style = task, catalog, style

    @functools.cached_property
    def own(self) -> str:
        """The task's instruction."""
        return self.task.instruction(self.style)

    @functools.cached_property
    def switch_pool(self) -> list[Task]:
        """The tasks a `switch:K` episode may start under: an extended task's source; for an original, the
        siblings of its scene with another instruction and goal."""
        task, catalog, style = self.task, self.catalog, self.style
        if task.kind != TaskKind.ORIGINAL:
            return [catalog.get(task.source)]
        return [
            t
            for t in catalog.scene_mates(task)
            if t.id != task.id and t.instruction(style) != self.own and t.goal != task.goal
        ]

    @functools.cached_property
    def _shuffle_pool(self) -> list[str]:
        """The other instructions of the task's scene (of its suite, for a scene with one task: libero_10's)."""
        task, style = self.task, self.style

        def others(tasks: Iterable[Task]) -> list[str]:
            return [i for t in tasks if t.id != task.id and (i := t.instruction(style)) != self.own]

        return others(self.catalog.scene_mates(task)) or others(t for t in self.catalog if t.suite == task.suite)

    def instruction(self, condition: str, init_index: int) -> str:
        """The instruction a policy receives for the task under a language `condition` (not `switch:K`)."""
        if condition == Condition.GIVEN:
            return self.own
        if condition == Condition.EMPTY:
            return ""
        if condition == Condition.SOURCE:
            return self.catalog.get(self.task.source).instruction(self.style)
        if condition == Condition.NONSENSE:
            return self.nonsense(init_index)
        if condition == Condition.SHUFFLED:
            if not self._shuffle_pool:
                raise CatalogError(f"no other instruction to shuffle in for {self.task.id}")
            # Deterministic and spread over the pool: the choice depends on the task and the init index only.
            return _pick(self._shuffle_pool, self.task.id, init_index)
        raise CatalogError(unknown_conditions_text([condition]))

    def nonsense(self, init_index: int) -> str:
        """As many words as the task's instruction has, drawn (seeded by the task and init index) from the words
        of every instruction of the catalog: a sentence of the benchmark's words that asks for nothing."""
        vocabulary = _vocabulary(self.catalog, self.style)
        seed = int.from_bytes(hashlib.sha256(f"{self.task.id}#nonsense#{init_index}".encode()).digest()[:8])
        words = np.random.default_rng(seed).integers(len(vocabulary), size=len(self.own.split()))
        return " ".join(vocabulary[i] for i in words)

    def switch_source(self, seed: int) -> Task:
        """The task whose instruction a `switch:K` episode starts under: one of `switch_pool`, chosen from the
        episode's seed."""
        if not self.switch_pool:
            raise CatalogError(f"switch: {self.task.id} has no sibling task in its scene to start under")
        return _pick(self.switch_pool, self.task.id, "switch", seed)

    def switch_episode(self, key: EpisodeKey, scene: str, watched: tuple[str, ...]) -> PlannedEpisode:
        """A `switch:K` episode (K from `key.condition`) of the task, set in `scene` and watching the goals of
        `watched`: under its first task's instruction until policy step K, then the task's own. A K the task
        never reaches is a CatalogError."""
        task = self.task
        k = switch_step(key.condition)
        if k is None:
            raise CatalogError(unknown_conditions_text([key.condition]))
        if k >= task.max_steps:
            raise CatalogError(
                f"{key.condition}: {task.id} ends at step {task.max_steps}, before its instruction would switch"
            )
        first = self.switch_source(key.seed)
        instruction = first.instruction(self.style)
        return PlannedEpisode(key, instruction, scene, watched, changes=((k, self.own),), started_as=first.id)


def switch_source(task: Task, catalog: Catalog, style: str, seed: int) -> Task:
    """The task whose instruction a `switch:K` episode of `task` starts under (`TaskLanguage.switch_source`)."""
    return TaskLanguage(task, catalog, style).switch_source(seed)


def switch_episode(
    key: EpisodeKey, task: Task, catalog: Catalog, style: str, scene: str, watched: tuple[str, ...]
) -> PlannedEpisode:
    """A `switch:K` episode of `task`, set in `scene` and watching `watched` (`TaskLanguage.switch_episode`)."""
    return TaskLanguage(task, catalog, style).switch_episode(key, scene, watched)


def condition_instruction(task: Task, catalog: Catalog, condition: str, style: str, init_index: int) -> str:
    """The instruction a policy receives for `task` under a language `condition` (`TaskLanguage.instruction`)."""
    return TaskLanguage(task, catalog, style).instruction(condition, init_index)


def without_switch_source(tasks: list[Task], catalog: Catalog, style: str = "libero") -> list[str]:
    """The ids of `tasks` that no `switch:K` episode can start under another instruction of: originals whose
    scene holds no other task of the catalog (libero_10's scenes in LangGap-99). A plan leaves their switch
    episodes out."""
    return [t.id for t in tasks if not TaskLanguage(t, catalog, style).switch_pool]


def switch_note(tasks: list[Task], catalog: Catalog, conditions: tuple[str, ...], style: str = "libero") -> str:
    """The line that says which tasks a plan with `switch:K` conditions leaves unswitched (empty: none)."""
    missing = without_switch_source(tasks, catalog, style) if any(map(switch_step, conditions)) else []
    if not missing:
        return ""
    shown = ", ".join(missing[:4]) + (f", … ({len(missing) - 4} more)" if len(missing) > 4 else "")
    return (
        f"note: {len(missing)} task(s) have no other task in their scene to start under; their {SWITCH}K "
        f"episodes are not planned: {shown}"
    )


def build_plan(
    tasks: list[Task],
    catalog: Catalog,
    *,
    episodes: int,
    seed: int = 0,
    conditions: tuple[str, ...] = (Condition.GIVEN.value,),
    style: str = "libero",
    first_init: int = 0,
    repeats: int = 1,
) -> list[PlannedEpisode]:
    """Episodes `first_init .. first_init+episodes-1` (init state k = episode k) of every task × condition,
    each `repeats` times with its own seed (same init state); no `switch:K` episode of a task that has nothing
    to start under (`without_switch_source`)."""
    if episodes < 1:
        raise CatalogParameterError("{episodes} must be at least 1, got {got}", got=episodes)
    unknown = unknown_conditions(conditions)
    if unknown:
        raise CatalogError(unknown_conditions_text(unknown))
    from langgap.catalog.files import init_states

    plan = []
    for task in tasks:
        available = init_states(task).shape[0]
        if first_init < 0 or first_init + episodes > available:
            raise InitStateError(
                f"{task.id} has {available} init states; init indices {first_init}..{first_init + episodes - 1} "
                "are out of range"
            )
        # What the task's episodes are set in, watch and are told, read from the catalog once for all of them.
        scene, language = catalog.scene_key(task), TaskLanguage(task, catalog, style)
        watched = tuple(mate.id for mate in catalog.scene_mates(task))
        for condition in conditions:
            k = switch_step(condition)
            if k and not language.switch_pool:
                continue
            for init_index in range(first_init, first_init + episodes):
                instruction = None if k else language.instruction(condition, init_index)
                for repeat in range(repeats):
                    key = EpisodeKey(task.id, init_index, episode_seed(seed, init_index, repeat), condition)
                    plan.append(
                        language.switch_episode(key, scene, watched)
                        if k
                        else PlannedEpisode(key, instruction, scene, watched)
                    )
    if not plan:
        raise CatalogError("switch: no selected task has another task in its scene to start under")
    return plan
