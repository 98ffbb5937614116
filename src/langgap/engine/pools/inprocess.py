"""The pool of one worker: this process (`--workers 0`). Nothing can stop an item here, so no timeouts."""

from __future__ import annotations

from langgap.catalog.catalog import Catalog
from langgap.engine.pools import Event, ItemDone, ItemFailed
from langgap.engine.runner import RunnerSetup, WorkFailure, WorkRunner
from langgap.engine.work import WorkItem


class InProcessPool:
    """Runs each submitted item in this process when polled; its runners use `catalog` (`setup.catalog` as this
    process loaded it; None: each loads it)."""

    def __init__(self, setup: RunnerSetup, catalog: Catalog | None = None):
        self.setup = setup
        self.catalog = catalog
        self._runners: dict[int, WorkRunner] = {}
        self._pending: list[tuple[int, WorkItem, int]] = []
        self._next_id = 0

    def spawn(self) -> int:
        worker, self._next_id = self._next_id, self._next_id + 1
        self._runners[worker] = WorkRunner(self.setup, worker=worker, catalog=self.catalog)
        return worker

    def submit(self, worker: int, item: WorkItem, attempt: int) -> None:
        self._pending.append((worker, item, attempt))

    def poll(self, timeout: float) -> list[Event]:
        events: list[Event] = []
        while self._pending:
            worker, item, attempt = self._pending.pop(0)
            try:
                events.append(ItemDone(worker, self._runners[worker].run(item, attempt)))
            except WorkFailure as exc:
                events.append(ItemFailed(worker, str(exc)))
        return events

    def kill(self, worker: int) -> None:
        self._runners.pop(worker).close()

    def close(self) -> None:
        for runner in self._runners.values():
            runner.close()
        self._runners.clear()
