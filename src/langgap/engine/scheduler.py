"""The one scheduling loop: work items onto a worker pool, with retries, timeouts, respawns and gaps.

It is generic over the items (`langgap.engine.work.WorkItem`: planned episodes, collections, searches,
probes, renders) and their results; it never looks at what kind of work an item is.

* Work goes out in *units*: consecutive items of one task, the tasks of a scene one after another, so
  a worker reuses its environment (soft resets), split when there are too few to keep every worker busy.
* An infrastructure failure (an exception outside the policy's action check, a worker that dies, an
  item past its timeout) puts the item back at the end of the queue until it has been attempted
  `max_attempts` times; then `make_gap` turns it into a gap (an episode's gap record: no verdict on
  the policy; other work refuses gaps, `langgap.engine.work.refuse_gap`).
* Failures with the same cause on `max_failure_streak` different items in a row (none finishing in
  between) stop the run (`RunStopped`): a dead policy server must not cost hours of retries, while one
  task that keeps crashing only costs its own attempts. Everything yielded before is intact.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Hashable, Iterator
from dataclasses import dataclass, field
from typing import Generic, TypeVar

from langgap.engine.pools import ItemDone, ItemFailed, WorkerLost, WorkerPool
from langgap.engine.work import WorkItem
from langgap.errors import ParameterError

POLL_S = 0.2
Item = TypeVar("Item", bound=WorkItem)
Result = TypeVar("Result")
# Called with (item, error, attempts) when an item's attempts are used up.
GapFactory = Callable[[Item, str, int], Result]


class RunStopped(ParameterError):
    """The run stopped after repeated infrastructure failures with one cause; a resume (`resume`) continues it."""

    exit_code = 4


def make_units(plan: list[Item], workers: int) -> deque[deque[Item]]:
    """Consecutive items of one task, the tasks of a scene one after another (so a worker's environment
    serves the next task of the same scene), split when there are too few tasks to keep every worker busy."""
    by_task: dict[str, list[Item]] = {}
    for item in sorted(plan, key=lambda p: p.scene):
        by_task.setdefault(item.task_id, []).append(item)
    pieces_per_task = max(1, -(-2 * workers // max(1, len(by_task))))
    units: deque[deque[Item]] = deque()
    for items in by_task.values():
        size = max(1, -(-len(items) // pieces_per_task))
        for start in range(0, len(items), size):
            units.append(deque(items[start : start + size]))
    return units


class Ledger(Generic[Item]):
    """The work left to do, and how often each item was attempted."""

    def __init__(self, plan: list[Item], workers: int, max_attempts: int):
        self.units = make_units(plan, workers)
        self.max_attempts = max_attempts
        self._attempts: dict[Hashable, int] = {}

    def __bool__(self) -> bool:
        return bool(self.units)

    def take(self) -> deque[Item]:
        return self.units.popleft()

    def give_back(self, items: deque[Item]) -> None:
        """Return items that were handed out but never started (they go first)."""
        if items:
            self.units.appendleft(items)

    def started(self, key: Hashable) -> int:
        """Count an attempt of `key`; returns its number."""
        self._attempts[key] = self._attempts.get(key, 0) + 1
        return self._attempts[key]

    def failed(self, item: Item) -> int | None:
        """Queue `item` for another attempt (None), or return its attempt count once they are used up.

        The retry goes last, so a failure that has one cause for every item shows on different
        items (and stops the run) before one item's attempts are spent.
        """
        attempts = self._attempts.get(item.key, 0)
        if attempts >= self.max_attempts:
            return attempts
        self.units.append(deque([item]))
        return None


@dataclass
class _Slot(Generic[Item]):
    """One worker as the scheduler sees it."""

    unit: deque[Item] = field(default_factory=deque)
    current: Item | None = None
    started_at: float = 0.0


class _Streak:
    """The items that failed in a row with the same cause."""

    def __init__(self, limit: int):
        self.limit = limit
        self.cause = ""
        self.items: set[Hashable] = set()

    def success(self) -> None:
        self.cause, self.items = "", set()

    def failure(self, item: WorkItem, cause: str) -> None:
        if cause != self.cause:
            self.cause, self.items = cause, set()
        self.items.add(item.key)
        if len(self.items) >= self.limit:
            raise RunStopped(
                "stopped after {count} {kind}s in a row failed with: {cause} "
                "(stored results are intact; fix the cause and run again with {resume}, where the command has it)",
                count=len(self.items),
                kind=item.kind,
                cause=cause,
            )


def schedule(
    plan: list[Item],
    pool: WorkerPool,
    *,
    workers: int,
    make_gap: GapFactory[Item, Result],
    max_attempts: int,
    max_failure_streak: int,
    timeout_s: float | None,
    clock: Callable[[], float] = time.monotonic,
) -> Iterator[Result]:
    """Run `plan` on `pool` with up to `workers` workers; yields every item's result (or gap) as it ends.

    An item's timeout is `timeout_s` times its `size` (the episodes' worth it may take). The pool stays
    open: whoever made it closes it.
    """
    ledger: Ledger[Item] = Ledger(plan, workers, max_attempts)
    slots: dict[int, _Slot[Item]] = {}
    streak = _Streak(max_failure_streak)

    def failed(item: Item, error: str) -> Iterator[Result]:
        attempts = ledger.failed(item)
        if attempts is not None:
            yield make_gap(item, error, attempts)
        streak.failure(item, error)

    def retire(worker: int, reason: str) -> Iterator[Result]:
        """A worker is gone: its item is charged, the rest of its unit goes back, a new worker takes over."""
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
            if isinstance(event, ItemDone):
                slot.current = None
                streak.success()
                yield event.result
            elif isinstance(event, ItemFailed):
                item, slot.current = slot.current, None
                if item is not None:
                    yield from failed(item, event.error)
            elif isinstance(event, WorkerLost):
                yield from retire(event.worker, event.reason)
        if timeout_s is not None:
            for worker in [w for w, s in slots.items() if s.current is not None]:
                limit = timeout_s * slots[worker].current.size
                if clock() - slots[worker].started_at > limit:
                    pool.kill(worker)
                    yield from retire(worker, f"{slots[worker].current.kind} timed out after {limit:.0f}s")
