"""What every backend shares: the queue of work units and the bookkeeping of attempts and gaps."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable

from langgap.catalog.catalog import load_catalog
from langgap.engine.episode import gap_record
from langgap.engine.plan import EpisodeKey, PlannedEpisode
from langgap.engine.runner import RunnerSetup
from langgap.records import EpisodeRecord


def make_units(
    plan: list[PlannedEpisode], workers: int, scene_of: Callable[[str], str] = str
) -> deque[deque[PlannedEpisode]]:
    """Consecutive episodes of one task (so a worker reuses its environment), split when there are too few
    tasks to keep every worker busy; tasks of one scene come one after another (`scene_of(task_id)`), so a
    worker's environment also serves the next task of the same scene."""
    by_task: dict[str, list[PlannedEpisode]] = {}
    for planned in sorted(plan, key=lambda p: scene_of(p.key.task_id)):
        by_task.setdefault(planned.key.task_id, []).append(planned)
    pieces_per_task = max(1, -(-2 * workers // max(1, len(by_task))))
    units: deque[deque[PlannedEpisode]] = deque()
    for episodes in by_task.values():
        size = max(1, -(-len(episodes) // pieces_per_task))
        for start in range(0, len(episodes), size):
            units.append(deque(episodes[start : start + size]))
    return units


class Ledger:
    """The work left to do, and how often each episode was attempted.

    An infrastructure failure puts the episode back at the front of the queue until it has been
    attempted `max_attempts` times; then it becomes a gap record.
    """

    def __init__(self, plan: list[PlannedEpisode], workers: int, setup: RunnerSetup, max_attempts: int):
        catalog = load_catalog(setup.catalog)
        self.units = make_units(
            plan, workers, lambda task_id: f"{catalog.get(task_id).suite}/{catalog.get(task_id).scene_task}"
        )
        self.setup = setup
        self.max_attempts = max_attempts
        self._count: dict[EpisodeKey, int] = {}

    def __bool__(self) -> bool:
        return bool(self.units)

    def take(self) -> deque[PlannedEpisode]:
        return self.units.popleft()

    def give_back(self, episodes: Iterable[PlannedEpisode]) -> None:
        """Return episodes that were handed out but never started."""
        episodes = deque(episodes)
        if episodes:
            self.units.appendleft(episodes)

    def upcoming(self, key: EpisodeKey) -> int:
        """The number the next attempt of `key` will have."""
        return self._count.get(key, 0) + 1

    def started(self, key: EpisodeKey) -> int:
        self._count[key] = self.upcoming(key)
        return self._count[key]

    def failed(self, planned: PlannedEpisode, error: str) -> EpisodeRecord | None:
        """Retry `planned` later, or return its gap record once its attempts are used up."""
        attempts = self._count.get(planned.key, 0)
        if attempts >= self.max_attempts:
            task = load_catalog(self.setup.catalog).get(planned.key.task_id)
            return gap_record(planned, task, policy_name=self.setup.policy, error=error, attempts=attempts)
        self.units.appendleft(deque([planned]))
        return None
