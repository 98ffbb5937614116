"""Shared rollouts (`--share-rollouts`): the planned episodes an instruction-blind policy plays identically, as
one work item.

A policy whose spec declares `reads_instruction=False` is told nothing that tells the tasks of one scene apart
but their source's goal (`TaskContext.for_policy`). Episodes of such a policy whose environment starts alike
(the same scene and init-state file, init index and seed: `TaskEnv.can_switch_to`), with the same step limit
and the same context as the policy sees it, get the same actions step for step, whatever their task or
condition: they run as one `SharedRollout`, judged as each member's episode (`run_shared_episode`). Only the
episodes whose records can be cut from that rollout exactly share it: never one that is filmed (its clip
would show the shared rollout past its own end). An instruction that switches re-asks the policy at the
switch, mid-chunk, so its actions can differ from an unswitched episode's: episodes share a rollout only
with episodes whose instruction switches at the same policy steps (`switch:K` ones of one K, with each other).
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import ClassVar

from langgap.catalog.catalog import Catalog
from langgap.catalog.files import init_states_path
from langgap.engine.context import planned_context
from langgap.engine.plan import PlannedEpisode
from langgap.policies import make_policy
from langgap.policies.base import PolicySpec


@dataclass(frozen=True)
class SharedRollout:
    """Planned episodes played as one rollout: a work item (`langgap.engine.work.WorkItem`) whose result is
    the list of its members' records."""

    kind: ClassVar[str] = "shared rollout"
    # One rollout runs to the members' common step limit, as one episode that fails does: one episode's
    # timeout (judging a few more goals per step costs little next to the physics).
    size: ClassVar[int] = 1

    members: tuple[PlannedEpisode, ...]

    @property
    def key(self) -> Hashable:
        return tuple(p.key for p in self.members)

    @property
    def task_id(self) -> str:
        return self.members[0].task_id

    @property
    def scene(self) -> str:
        return self.members[0].scene


def rollout_key(planned: PlannedEpisode, catalog: Catalog, spec: PolicySpec, style: str) -> Hashable | None:
    """What a planned episode of a policy with `spec` shares its rollout by (None: it runs on its own)."""
    if spec.reads_instruction or planned.film:
        return None
    task = catalog.get(planned.task_id)
    context = planned_context(planned, task, catalog, style).for_policy(spec)
    # The start (`TaskEnv.can_switch_to`), everything the policy is told (the context holds the init index, seed
    # and step limit), and when it is asked again because its instruction switched.
    start = task.suite, task.scene_task, planned.scene, str(init_states_path(task))
    return *start, context, change_steps(planned)


def change_steps(planned: PlannedEpisode) -> tuple[int, ...]:
    """The policy steps at which `planned`'s instruction changes."""
    return tuple(sorted(step for step, _ in planned.changes))


def share_rollouts(
    plan: list[PlannedEpisode], catalog: Catalog, spec: PolicySpec, style: str
) -> list[PlannedEpisode | SharedRollout]:
    """`plan` as work items: the episodes with one `rollout_key` as one `SharedRollout`, every other one alone."""
    groups: dict[Hashable, list[PlannedEpisode]] = {}
    alone: list[PlannedEpisode | SharedRollout] = []
    for planned in plan:
        key = rollout_key(planned, catalog, spec, style)
        if key is None:
            alone.append(planned)
        else:
            groups.setdefault(key, []).append(planned)
    shared = [members[0] if len(members) == 1 else SharedRollout(tuple(members)) for members in groups.values()]
    return [*alone, *shared]


def policy_spec(name: str, args: dict[str, str]) -> PolicySpec:
    """The spec of policy `name` built with `args` (built here, in the driver, and closed again)."""
    policy = make_policy(name, args)
    try:
        return policy.spec
    finally:
        if hasattr(policy, "close"):
            policy.close()
