"""Executing one planned episode and turning its outcome into a stored record.

Besides success, every step evaluates the goals of all tasks set in the same scene (the task's
scene mates, its source included). The record says which of them became true and when, and the
episode is classified by what the policy did *instead* of its task:
`success`, `did_source_task` (an extended task's policy performed the original task of the scene:
the memorisation signature), `did_other_task`, `no_goal_reached`, or `policy_error` (the policy
returned a malformed action).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from datetime import UTC, datetime

import numpy as np

from langgap import stack
from langgap.catalog.catalog import Catalog
from langgap.catalog.files import scene_key
from langgap.catalog.task import Task
from langgap.engine.context import task_context
from langgap.engine.plan import PlannedEpisode
from langgap.engine.rollout import StepHook, run_episode
from langgap.policies.base import Policy, PolicyOutputError
from langgap.records import EpisodeRecord
from langgap.sim.env import TaskEnv
from langgap.version import code_version

OUTCOMES = ("success", "did_source_task", "did_other_task", "no_goal_reached", "policy_error", "gap")


def classify(task: Task, success: bool, reached: dict[str, int]) -> str:
    """What the episode achieved, from the goals that became true during it."""
    if success:
        return "success"
    if task.kind == "extended" and task.source in reached:
        return "did_source_task"
    if any(name != task.id for name in reached):
        return "did_other_task"
    return "no_goal_reached"


def scene_goals(task: Task, catalog: Catalog) -> dict[str, tuple[tuple[str, ...], ...]]:
    """The goals (LIBERO form) of every task in `task`'s scene, keyed by task id."""
    return {mate.id: tuple(p.as_libero() for p in mate.goal) for mate in catalog.scene_mates(task)}


def _record(planned: PlannedEpisode, task: Task, **values) -> EpisodeRecord:
    key = planned.key
    return EpisodeRecord(
        task_id=key.task_id,
        init_index=key.init_index,
        seed=key.seed,
        condition=key.condition,
        instruction=planned.instruction,
        instruction_sha256=planned.instruction_sha256,
        catalog=task.catalog,
        suite=task.suite,
        kind=task.kind,
        dimension=task.dimension,
        split=task.split,
        source=task.source,
        scene=scene_key(task),
        max_steps=task.max_steps,
        physics=stack.physics_stack(),
        code_version=code_version(),
        finished_at=datetime.now(UTC).isoformat(timespec="seconds"),
        **values,
    )


def execute_episode(
    planned: PlannedEpisode,
    task: Task,
    catalog: Catalog,
    env: TaskEnv,
    policy: Policy,
    *,
    policy_name: str,
    policy_hash: str,
    style: str,
    worker: int = 0,
    attempts: int = 1,
    on_step: StepHook | None = None,
) -> EpisodeRecord:
    """Run one planned episode. A malformed action is a policy failure (recorded); any other exception
    propagates, for the caller to treat as an infrastructure error."""
    key = planned.key
    context = task_context(
        task,
        catalog,
        init_index=key.init_index,
        seed=key.seed,
        style=style,
        condition=key.condition,
        instruction=planned.instruction,
    )
    started = time.perf_counter()
    common = dict(policy=policy_name, policy_config_hash=policy_hash, worker=worker, attempts=attempts)
    try:
        result = run_episode(env, policy, context, watch=scene_goals(task, catalog), on_step=on_step)
    except PolicyOutputError as exc:
        return _record(
            planned,
            task,
            status="done",
            success=False,
            outcome="policy_error",
            failure_kind="policy",
            error=str(exc),
            steps=env.steps,
            policy_calls=0,
            t0_hash=env.t0_hash or "",
            wall_time_s=time.perf_counter() - started,
            **common,
        )
    return _record(
        planned,
        task,
        status="done",
        success=result.success,
        outcome=classify(task, result.success, result.reached),
        failure_kind=None if result.success else "policy",
        error=None,
        steps=result.steps,
        policy_calls=result.policy_calls,
        t0_hash=result.t0_hash,
        reached=result.reached,
        goals_at_start=result.at_start,
        goals_at_end=result.at_end,
        wall_time_s=time.perf_counter() - started,
        **common,
    )


def gap_record(planned: PlannedEpisode, task: Task, *, policy_name: str, error: str, attempts: int) -> EpisodeRecord:
    """The record of an episode that infrastructure failed to run (no verdict on the policy)."""
    return _record(
        planned,
        task,
        status="gap",
        success=False,
        outcome="gap",
        failure_kind="infra",
        error=error,
        steps=0,
        policy_calls=0,
        t0_hash="",
        policy=policy_name,
        policy_config_hash="",
        attempts=attempts,
        wall_time_s=0.0,
        worker=-1,
    )


def video_hook(env: TaskEnv, frames: list[np.ndarray], cameras: tuple[str, ...]) -> Callable:
    """A step hook that appends one frame (the cameras side by side) per step."""

    def hook(_env: TaskEnv, _step: int, _action: np.ndarray) -> None:
        frames.append(np.concatenate([env.render(c) for c in cameras], axis=1))

    return hook
