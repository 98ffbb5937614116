"""Building the `TaskContext` a policy is reset with."""

from __future__ import annotations

from langgap.catalog.catalog import Catalog
from langgap.catalog.task import DEFAULT_STYLE, Task
from langgap.policies.base import TaskContext


def task_context(
    task: Task,
    catalog: Catalog,
    *,
    init_index: int,
    seed: int,
    style: str = DEFAULT_STYLE,
    condition: str = "given",
    instruction: str | None = None,
    privileged: bool = False,
) -> TaskContext:
    """The context for one episode of `task`; `instruction` overrides the catalog sentence (conditions)."""
    return TaskContext(
        task_id=task.id,
        suite=task.suite,
        instruction=task.instruction(style) if instruction is None else instruction,
        goal=tuple(task.goal_strings),
        source_goal=tuple(catalog.get(task.source).goal_strings),
        init_index=init_index,
        seed=seed,
        max_steps=task.max_steps,
        condition=condition,
    )
