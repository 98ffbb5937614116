"""Executing one planned episode and turning its outcome into a stored record.

Besides success, every step evaluates the goals of all tasks set in the same scene (the task's
scene mates, its source included). The record says which of them became true and when, and the
episode is classified by what the policy did *instead* of its task:
one of `langgap.vocabulary.Outcome` (`did_source_task` is the memorisation signature: an extended
task's policy performed the original task of the scene).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from datetime import UTC, datetime

import numpy as np

from langgap import stack
from langgap.catalog.catalog import Catalog
from langgap.catalog.task import Task
from langgap.engine.context import planned_context
from langgap.engine.plan import PlannedEpisode
from langgap.engine.rollout import RolloutResult, StepHook, run_episode, run_shared_episode
from langgap.errors import one_line
from langgap.goals import Goal
from langgap.policies.base import Policy, PolicyOutputError
from langgap.records import EpisodeRecord, FailureKind, Status, classify
from langgap.sim.env import SETTLE_STEPS, TaskEnv
from langgap.version import code_version
from langgap.vocabulary import Outcome


@dataclass(frozen=True)
class EpisodeSettings:
    """What every episode executor takes besides the episode, its environment and its policy: the same for
    every episode a worker runs with one built policy (the runner builds it with the policy)."""

    policy_name: str  # the name the policy was asked for by (`langgap eval --policy`), stored in each record
    policy_hash: str  # `config_hash` of the built policy's config ("": not recorded, as `check-policy` runs it)
    style: str  # the instruction style the policy is told (`RunSpec.style`)
    worker: int = 0  # the worker the episodes run on, stored in each record


def scene_goals(task: Task, catalog: Catalog) -> dict[str, Goal]:
    """The goals of every task in `task`'s scene, keyed by task id."""
    return {mate.id: mate.goal for mate in catalog.scene_mates(task)}


def watched_goals(planned: PlannedEpisode, catalog: Catalog) -> dict[str, Goal]:
    """The goals `planned` watches (`PlannedEpisode.watched`: its scene's, as the plan found them), keyed by task id."""
    return {task_id: catalog.get(task_id).goal for task_id in planned.watched}


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
        scene=planned.scene,
        max_steps=task.max_steps,
        settle_steps=SETTLE_STEPS,
        code_version=code_version(),
        finished_at=datetime.now(UTC).isoformat(timespec="seconds"),
        **values,
    )


def _switched(planned: PlannedEpisode, instructions: list[tuple[int, str]]) -> tuple[str, int] | None:
    """(the first instruction's task, the step the instruction changed) of a switch episode that got that far."""
    if not planned.started_as or len(instructions) < 2:
        return None
    return planned.started_as, instructions[1][0]


def _policy_fields(env: TaskEnv, policy: Policy, settings: EpisodeSettings, attempts: int) -> dict:
    """The record fields that say which policy ran, what it saw, and where."""
    return dict(
        policy=settings.policy_name,
        policy_config_hash=settings.policy_hash,
        sees_state=policy.spec.sees_state,
        sees_goal=policy.spec.sees_goal,
        cameras=list(policy.spec.cameras),
        image_size=policy.spec.image_size if policy.spec.cameras else 0,
        worker=settings.worker,
        attempts=attempts,
        physics=stack.physics_stack(env.options.stepping, env.options.seed_scheme),
    )


def _policy_error_record(
    planned: PlannedEpisode, task: Task, error: PolicyOutputError, env: TaskEnv, wall_time_s: float, common: dict
) -> EpisodeRecord:
    """The record of an episode that ended on a malformed action (`error`, stored after the policy's name)."""
    return _record(
        planned,
        task,
        status=Status.DONE,
        success=False,
        outcome=Outcome.POLICY_ERROR,
        failure_kind=FailureKind.POLICY,
        error=f"{common['policy']}: {error}",
        steps=env.steps,
        policy_calls=0,
        t0_hash=env.t0_hash or "",
        wall_time_s=wall_time_s,
        **common,
    )


def _judged_record(
    planned: PlannedEpisode, task: Task, result: RolloutResult, wall_time_s: float, common: dict
) -> EpisodeRecord:
    """The record of an episode the policy played to its end."""
    return _record(
        planned,
        task,
        status=Status.DONE,
        success=result.success,
        outcome=classify(
            task.id,
            task.kind,
            task.source,
            result.success,
            result.reached,
            wrong_order=result.wrong_order,
            switched=_switched(planned, result.instructions),
        ),
        failure_kind=None if result.success else FailureKind.POLICY,
        error=None,
        steps=result.steps,
        policy_calls=result.policy_calls,
        t0_hash=result.t0_hash,
        reached=result.reached,
        goals_at_start=result.at_start,
        goals_at_end=result.at_end,
        instructions=[list(change) for change in result.instructions],
        wall_time_s=wall_time_s,
        **common,
    )


def execute_episode(
    planned: PlannedEpisode,
    task: Task,
    catalog: Catalog,
    env: TaskEnv,
    policy: Policy,
    settings: EpisodeSettings,
    *,
    attempts: int = 1,
    on_step: StepHook | None = None,
) -> EpisodeRecord:
    """Run one planned episode (its `attempts`-th try). A malformed action is a policy failure (recorded);
    any other exception propagates, for the caller to treat as an infrastructure error."""
    context = planned_context(planned, task, catalog, settings.style)
    started = time.perf_counter()
    common = _policy_fields(env, policy, settings, attempts)
    try:
        result = run_episode(
            env, policy, context, watch=watched_goals(planned, catalog), on_step=on_step, changes=planned.changes
        )
    except PolicyOutputError as exc:
        return _policy_error_record(planned, task, exc, env, time.perf_counter() - started, common)
    return _judged_record(planned, task, result, time.perf_counter() - started, common)


def execute_shared(
    members: tuple[PlannedEpisode, ...],
    catalog: Catalog,
    env: TaskEnv,
    policy: Policy,
    settings: EpisodeSettings,
    *,
    attempts: int = 1,
) -> list[EpisodeRecord]:
    """Run planned episodes that share one rollout (`langgap.engine.sharing`) as that one rollout; each gets
    the record its own episode would have (`run_shared_episode`), the wall time measured to its own end.

    A malformed action ends every episode still running as a policy failure, as it would have ended each.
    Any other exception ends the episodes still running as gaps (infrastructure: a resume runs them again)
    when some ended before it, and propagates (the whole rollout retried) when none did."""
    tasks = {p.key.task_id: catalog.get(p.key.task_id) for p in members}
    lead = members[0]
    context = planned_context(lead, tasks[lead.key.task_id], catalog, settings.style)
    common = _policy_fields(env, policy, settings, attempts)
    started = time.perf_counter()
    goals = {task_id: task.goal for task_id, task in tasks.items()}
    rollout = run_shared_episode(
        env,
        policy,
        context,
        goals,
        watch=watched_goals(lead, catalog),
        change_steps=[step for step, _ in lead.changes],
    )
    error = rollout.error
    if error is not None and not isinstance(error, PolicyOutputError) and not rollout.results:
        raise error
    records = []
    for planned in members:
        task = tasks[planned.key.task_id]
        result = rollout.results.get(task.id)
        if result is not None:
            result = replace(result, instructions=_own_instructions(planned, result.instructions))
            records.append(_judged_record(planned, task, result, rollout.ended_after_s[task.id], common))
        elif isinstance(error, PolicyOutputError):
            wall = time.perf_counter() - started
            records.append(_policy_error_record(planned, task, error, env, wall, common))
        else:
            records.append(
                gap_record(
                    planned,
                    task,
                    policy_name=settings.policy_name,
                    error=one_line(error),
                    attempts=attempts,
                    physics=common["physics"],
                )
            )
    return records


def _own_instructions(planned: PlannedEpisode, sent: list[tuple[int, str]]) -> list[tuple[int, str]]:
    """The steps of the instructions a shared rollout `sent` before `planned`'s episode ended, each with the
    instruction `planned`'s own episode sent there: its first, then its changes in order."""
    texts = [planned.instruction, *(text for _, text in sorted(planned.changes))]
    return [(step, text) for (step, _), text in zip(sent, texts, strict=False)]


def gap_record(
    planned: PlannedEpisode, task: Task, *, policy_name: str, error: str, attempts: int, physics: dict
) -> EpisodeRecord:
    """The record of an episode that infrastructure failed to run (no verdict on the policy)."""
    return _record(
        planned,
        task,
        physics=physics,
        status=Status.GAP,
        success=False,
        outcome=Outcome.GAP,
        failure_kind=FailureKind.INFRA,
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


class VideoHook:
    """A step hook that appends one frame (the cameras side by side) every `every` steps; its cameras are
    rendered inside those steps, where robosuite samples its observables (`cameras_at`)."""

    def __init__(self, env: TaskEnv, frames: list[np.ndarray], cameras: tuple[str, ...], every: int = 1):
        self.env, self.frames, self.cameras, self.every = env, frames, cameras, every

    def cameras_at(self, step: int) -> tuple[str, ...]:
        """The cameras this hook reads after policy step `step`."""
        return self.cameras if step % self.every == 0 else ()

    def __call__(self, _env: TaskEnv, step: int, _action: np.ndarray) -> None:
        if step % self.every == 0:
            self.frames.append(np.concatenate([self.env.render(c) for c in self.cameras], axis=1))


def video_hook(env: TaskEnv, frames: list[np.ndarray], cameras: tuple[str, ...], every: int = 1) -> VideoHook:
    """A step hook that appends one frame (the cameras side by side) every `every` steps."""
    return VideoHook(env, frames, cameras, every)
