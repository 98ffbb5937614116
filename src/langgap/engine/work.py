"""Work items: what the scheduler hands to workers. Every kind of episode work is one.

A planned evaluation episode (`langgap.engine.plan.PlannedEpisode`) is the first kind, and a shared rollout
of several (`langgap.engine.sharing.SharedRollout`: an instruction-blind policy's) the second. The others are
`Job`s, frozen dataclasses that live with the feature they serve and do their work in `perform`, on a
worker's `JobHost` (the runner, which lends them the catalog and a kept environment): a demonstration
collection of one task (`langgap.demos.collect`), a demonstration rendered (`langgap.demos.render`),
the search for demonstrations of one task (`langgap.gate.search`), and the gate's probes of a scene
(`langgap.gate.probes`). Whichever the kind, the scheduler gives it the same retries, timeouts, gaps
and fail-fast rule, and every backend runs it.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

from langgap.errors import LangGapError

if TYPE_CHECKING:
    from pathlib import Path

    from langgap.catalog.catalog import Catalog
    from langgap.catalog.task import Task
    from langgap.sim.env import EnvOptions, TaskEnv


class WorkItem(Protocol):
    """What the scheduler needs of a work item."""

    kind: ClassVar[str]  # what work it is (for messages; the runner dispatches on the item's type)

    @property
    def key(self) -> Hashable:
        """Unique among the items of one schedule: attempts are counted per key."""
        ...

    @property
    def task_id(self) -> str:
        """The task it works on: consecutive items of one task go to one worker (its environment is kept)."""
        ...

    @property
    def scene(self) -> str:
        """The scene it is set in: the tasks of a scene are handed out one after another."""
        ...

    @property
    def size(self) -> int:
        """How many episodes' worth of simulation it may take: its timeout is that many episode timeouts."""
        ...


class JobHost(Protocol):
    """What a `Job` may use of the worker that performs it (`langgap.engine.runner.WorkRunner`)."""

    @property
    def catalog(self) -> Catalog:
        """The catalog the work's tasks come from."""
        ...

    @property
    def output_dir(self) -> Path:
        """Where work writes its files (a run's or a command's output directory)."""
        ...

    def kept_env(self, task: Task, options: EnvOptions) -> TaskEnv:
        """An environment of `task` built with `options`, kept while consecutive work asks for the same."""
        ...


class Job:
    """A work item that does its own work on a worker (mixed into a frozen dataclass)."""

    kind: ClassVar[str] = "job"

    @property
    def key(self) -> Hashable:
        return self

    @property
    def scene(self) -> str:
        return ""

    @property
    def size(self) -> int:
        return 1

    def perform(self, runner: JobHost) -> Any:
        """Do the work on a worker; an exception is an infrastructure failure (retried, then a gap)."""
        raise NotImplementedError


class AttemptsExhausted(LangGapError):
    """A work item failed on every attempt (each one a `WorkFailure` on its worker); work other than an evaluation
    episode has no gap to record, so the command fails."""

    exit_code = 4


def refuse_gap(item: WorkItem, error: str, attempts: int) -> Any:
    """The gap factory of work whose results cannot have gaps: the whole command fails with one line."""
    raise AttemptsExhausted(f"{item.kind} {item.task_id} failed {attempts} time(s): {error}")
