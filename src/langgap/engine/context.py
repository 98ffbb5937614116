"""Building the `TaskContext` a policy is reset with."""

from __future__ import annotations

from langgap.catalog.catalog import Catalog
from langgap.catalog.task import DEFAULT_STYLE, Task
from langgap.engine.plan import PlannedEpisode
from langgap.policies.base import PrivilegedContext, TaskContext
from langgap.vocabulary import Condition


def task_context(
    task: Task,
    catalog: Catalog,
    *,
    init_index: int,
    seed: int,
    style: str = DEFAULT_STYLE,
    condition: str = Condition.GIVEN.value,
    instruction: str | None = None,
    instruction_goals: tuple[tuple[str, str], ...] = (),
) -> TaskContext:
    """The full context for one episode of `task` (privileged part included: the rollout gives each
    policy only what its spec allows); `instruction` overrides the catalog sentence (conditions);
    `instruction_goals` names the goals of the episode's instructions that ask for another task's."""
    return TaskContext(
        instruction=task.instruction(style) if instruction is None else instruction,
        suite=task.suite,
        init_index=init_index,
        seed=seed,
        max_steps=task.max_steps,
        privileged=PrivilegedContext(
            task_id=task.id,
            condition=condition,
            goal=tuple(str(p) for p in task.bddl_goal),
            source_goal=tuple(str(p) for p in catalog.get(task.source).bddl_goal),
            goal_expression=str(task.goal),
            instruction_goals=instruction_goals,
        ),
    )


def planned_context(planned: PlannedEpisode, task: Task, catalog: Catalog, style: str) -> TaskContext:
    """The context of one planned episode of `task`: its init state, seed, condition and first instruction;
    a switch's first instruction asks for its first task's goal (what a reference that follows it pursues)."""
    key = planned.key
    return task_context(
        task,
        catalog,
        init_index=key.init_index,
        seed=key.seed,
        style=style,
        condition=key.condition,
        instruction=planned.instruction,
        instruction_goals=((planned.instruction, str(catalog.get(planned.started_as).goal)),)
        if planned.started_as
        else (),
    )
