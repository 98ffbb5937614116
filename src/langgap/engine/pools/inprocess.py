"""The pool of one worker: this process (`--workers 0`). Nothing can stop an episode here, so no timeouts."""

from __future__ import annotations

from langgap.engine.plan import PlannedEpisode
from langgap.engine.pools import EpisodeDone, EpisodeFailed, Event
from langgap.engine.runner import EpisodeFailure, EpisodeRunner, RunnerSetup


class InProcessPool:
    """Runs each submitted episode in this process when polled."""

    def __init__(self, setup: RunnerSetup):
        self.setup = setup
        self._runners: dict[int, EpisodeRunner] = {}
        self._pending: list[tuple[int, PlannedEpisode, int]] = []
        self._next_id = 0

    def spawn(self) -> int:
        worker, self._next_id = self._next_id, self._next_id + 1
        self._runners[worker] = EpisodeRunner(self.setup, worker=worker)
        return worker

    def submit(self, worker: int, planned: PlannedEpisode, attempt: int) -> None:
        self._pending.append((worker, planned, attempt))

    def poll(self, timeout: float) -> list[Event]:
        events: list[Event] = []
        while self._pending:
            worker, planned, attempt = self._pending.pop(0)
            try:
                events.append(EpisodeDone(worker, self._runners[worker].run(planned, attempt)))
            except EpisodeFailure as exc:
                events.append(EpisodeFailed(worker, str(exc)))
        return events

    def kill(self, worker: int) -> None:
        self._runners.pop(worker).close()

    def close(self) -> None:
        for runner in self._runners.values():
            runner.close()
        self._runners.clear()
