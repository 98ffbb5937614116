"""The one scheduling loop: planned episodes onto a worker pool, with retries, timeouts, respawns and gaps.

* Work goes out in *units*: consecutive episodes of one scene, so a worker reuses its environment
  (soft resets), split when there are too few to keep every worker busy.
* An infrastructure failure (an exception outside the policy's action check, a worker that dies, an
  episode past its timeout) puts the episode back at the end of the queue until it has been
  attempted `max_attempts` times; then it becomes a gap record (no verdict on the policy).
* Failures with the same cause on `max_failure_streak` different episodes in a row (no episode
  finishing in between) stop the run (`RunStopped`): a dead policy server must not cost hours of
  retries, while one task that keeps crashing only costs its own attempts. Everything yielded
  before is intact.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from langgap.engine.plan import PlannedEpisode
from langgap.engine.pools import EpisodeDone, EpisodeFailed, WorkerLost, WorkerPool
from langgap.errors import LangGapError
from langgap.records import EpisodeKey, EpisodeRecord

POLL_S = 0.2
# Called with (episode, error, attempts) when an episode's attempts are used up.
GapFactory = Callable[[PlannedEpisode, str, int], EpisodeRecord]


class RunStopped(LangGapError):
    """The run stopped after repeated infrastructure failures with one cause; `--resume` continues it."""

    exit_code = 4


def make_units(plan: list[PlannedEpisode], workers: int) -> deque[deque[PlannedEpisode]]:
    """Consecutive episodes of one task, the tasks of a scene one after another (so a worker's environment
    serves the next task of the same scene), split when there are too few tasks to keep every worker busy."""
    by_task: dict[str, list[PlannedEpisode]] = {}
    for planned in sorted(plan, key=lambda p: p.scene):
        by_task.setdefault(planned.key.task_id, []).append(planned)
    pieces_per_task = max(1, -(-2 * workers // max(1, len(by_task))))
    units: deque[deque[PlannedEpisode]] = deque()
    for episodes in by_task.values():
        size = max(1, -(-len(episodes) // pieces_per_task))
        for start in range(0, len(episodes), size):
            units.append(deque(episodes[start : start + size]))
    return units


class Ledger:
    """The work left to do, and how often each episode was attempted."""

    def __init__(self, plan: list[PlannedEpisode], workers: int, max_attempts: int):
        self.units = make_units(plan, workers)
        self.max_attempts = max_attempts
        self._attempts: dict[EpisodeKey, int] = {}

    def __bool__(self) -> bool:
        return bool(self.units)

    def take(self) -> deque[PlannedEpisode]:
        return self.units.popleft()

    def give_back(self, episodes: deque[PlannedEpisode]) -> None:
        """Return episodes that were handed out but never started (they go first)."""
        if episodes:
            self.units.appendleft(episodes)

    def started(self, key: EpisodeKey) -> int:
        """Count an attempt of `key`; returns its number."""
        self._attempts[key] = self._attempts.get(key, 0) + 1
        return self._attempts[key]

    def failed(self, planned: PlannedEpisode) -> int | None:
        """Queue `planned` for another attempt (None), or return its attempt count once they are used up.

        The retry goes last, so a failure that has one cause for every episode shows on different
        episodes (and stops the run) before one episode's attempts are spent.
        """
        attempts = self._attempts.get(planned.key, 0)
        if attempts >= self.max_attempts:
            return attempts
        self.units.append(deque([planned]))
        return None


@dataclass
class _Slot:
    """One worker as the scheduler sees it."""

    unit: deque[PlannedEpisode] = field(default_factory=deque)
    current: PlannedEpisode | None = None
    started_at: float = 0.0


class _Streak:
    """The episodes that failed in a row with the same cause."""

    def __init__(self, limit: int):
        self.limit = limit
        self.cause = ""
        self.episodes: set[EpisodeKey] = set()

    def success(self) -> None:
        self.cause, self.episodes = "", set()

    def failure(self, key: EpisodeKey, cause: str) -> None:
        if cause != self.cause:
            self.cause, self.episodes = cause, set()
        self.episodes.add(key)
        if len(self.episodes) >= self.limit:
            raise RunStopped(
                f"stopped after {len(self.episodes)} episodes in a row failed with: {cause} "
                "(stored episodes are intact; fix the cause and --resume)"
            )


def schedule(
    plan: list[PlannedEpisode],
    pool: WorkerPool,
    *,
    workers: int,
    make_gap: GapFactory,
    max_attempts: int,
    max_failure_streak: int,
    timeout_s: float | None,
    clock: Callable[[], float] = time.monotonic,
) -> Iterator[EpisodeRecord]:
    """Run `plan` on `pool` with up to `workers` workers; yields every episode's record (or gap) as it ends.

    The pool stays open: whoever made it closes it.
    """
    ledger = Ledger(plan, workers, max_attempts)
    slots: dict[int, _Slot] = {}
    streak = _Streak(max_failure_streak)

    def failed(planned: PlannedEpisode, error: str) -> Iterator[EpisodeRecord]:
        attempts = ledger.failed(planned)
        if attempts is not None:
            yield make_gap(planned, error, attempts)
        streak.failure(planned.key, error)

    def retire(worker: int, reason: str) -> Iterator[EpisodeRecord]:
        """A worker is gone: its episode is charged, the rest of its unit goes back, a new worker takes over."""
        slot = slots.pop(worker)
        ledger.give_back(slot.unit)
        if slot.current is not None:
            yield from failed(slot.current, reason)
        if ledger and len(slots) < workers:
            slots[pool.spawn()] = _Slot()

    for _ in range(min(workers, len(ledger.units))):
        slots[pool.spawn()] = _Slot()
    while ledger or any(s.current is not None or s.unit for s in slots.values()):
        for worker, slot in slots.items():
            if slot.current is None and not slot.unit and ledger:
                slot.unit = ledger.take()
            if slot.current is None and slot.unit:
                slot.current = slot.unit.popleft()
                slot.started_at = clock()
                pool.submit(worker, slot.current, ledger.started(slot.current.key))
        for event in pool.poll(POLL_S):
            slot = slots.get(event.worker)
            if slot is None:  # a worker retired earlier (e.g. killed for a timeout)
                continue
            if isinstance(event, EpisodeDone):
                slot.current = None
                streak.success()
                yield event.record
            elif isinstance(event, EpisodeFailed):
                episode, slot.current = slot.current, None
                if episode is not None:
                    yield from failed(episode, event.error)
            elif isinstance(event, WorkerLost):
                yield from retire(event.worker, event.reason)
        if timeout_s is not None:
            for worker in [w for w, s in slots.items() if s.current is not None]:
                if clock() - slots[worker].started_at > timeout_s:
                    pool.kill(worker)
                    yield from retire(worker, f"episode timed out after {timeout_s:.0f}s")
