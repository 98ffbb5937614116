"""Scheduling episodes in-process or on W local worker processes.

Backends only schedule: they hand `PlannedEpisode`s to `EpisodeRunner`s and yield `EpisodeRecord`s.
Infrastructure failures (an exception outside the policy's action check, a worker that dies, an
episode past its timeout) are retried up to `max_attempts` times in a fresh runner; after that the
episode is yielded as a gap record.

Worker processes are started with `spawn` (no simulator or GL state crosses a fork), build their
environment lazily, get the episodes of one task at a time (so the environment is reused), and exit
on their own if the scheduling process dies.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import queue
import threading
import time
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field

from langgap.engine.plan import PlannedEpisode
from langgap.engine.runner import EpisodeFailure, EpisodeRunner, RunnerSetup
from langgap.engine.scheduling import Ledger
from langgap.records import EpisodeRecord

DEFAULT_TIMEOUT_S = 900.0
DEFAULT_MAX_ATTEMPTS = 3
_POLL_S = 0.2


def run_in_process(
    plan: list[PlannedEpisode], setup: RunnerSetup, *, max_attempts: int = DEFAULT_MAX_ATTEMPTS
) -> Iterator[EpisodeRecord]:
    """Run the plan sequentially in this process (no timeout enforcement)."""
    runner = EpisodeRunner(setup)
    ledger = Ledger(plan, 1, setup, max_attempts)
    try:
        while ledger:
            unit = ledger.take()
            while unit:
                planned = unit.popleft()
                try:
                    yield runner.run(planned, ledger.started(planned.key))
                except EpisodeFailure as exc:
                    if (gap := ledger.failed(planned, str(exc))) is not None:
                        yield gap
    finally:
        runner.close()


# -- worker processes -----------------------------------------------------------------------------


def _exit_with_parent(parent_pid: int) -> None:
    """Kill this worker as soon as its scheduler is gone (e.g. `kill -9`), so no orphan keeps simulating."""
    while True:
        if os.getppid() != parent_pid:
            os._exit(1)
        time.sleep(0.5)


def worker_main(worker: int, setup: RunnerSetup, inbox, outbox, parent_pid: int) -> None:
    """Entry point of a worker process: run the units it is sent until it receives None."""
    threading.Thread(target=_exit_with_parent, args=(parent_pid,), daemon=True).start()
    runner = EpisodeRunner(setup, worker=worker)
    try:
        while (item := inbox.get()) is not None:
            for planned, attempt in item:
                outbox.put(("started", worker, planned.key))
                try:
                    outbox.put(("record", worker, runner.run(planned, attempt)))
                except EpisodeFailure as exc:
                    outbox.put(("failed", worker, planned.key, str(exc)))
            outbox.put(("idle", worker, None))
    finally:
        runner.close()


@dataclass
class _Worker:
    process: mp.Process
    inbox: object
    assigned: deque[PlannedEpisode] = field(default_factory=deque)
    current: PlannedEpisode | None = None
    started_at: float = 0.0
    busy: bool = False


class LocalBackend:
    """W worker processes on this machine."""

    def __init__(self, workers: int, *, timeout_s: float = DEFAULT_TIMEOUT_S, max_attempts: int = DEFAULT_MAX_ATTEMPTS):
        self.workers = max(1, workers)
        self.timeout_s = timeout_s
        self.max_attempts = max_attempts

    def run(self, plan: list[PlannedEpisode], setup: RunnerSetup) -> Iterator[EpisodeRecord]:
        context = mp.get_context("spawn")
        outbox = context.Queue()
        ledger = Ledger(plan, self.workers, setup, self.max_attempts)
        workers: dict[int, _Worker] = {}
        next_id = 0

        def spawn() -> None:
            nonlocal next_id
            inbox = context.Queue()
            process = context.Process(
                target=worker_main,
                args=(next_id, setup, inbox, outbox, os.getpid()),
                daemon=True,
                name=f"langgap-worker-{next_id}",
            )
            process.start()
            workers[next_id] = _Worker(process, inbox)
            next_id += 1

        for _ in range(min(self.workers, len(ledger.units))):
            spawn()
        try:
            while ledger or any(w.busy for w in workers.values()):
                for state in workers.values():
                    if not state.busy and ledger:
                        state.assigned = ledger.take()
                        state.busy = True
                        state.started_at = time.monotonic()
                        state.inbox.put([(p, ledger.upcoming(p.key)) for p in state.assigned])
                try:
                    message = outbox.get(timeout=_POLL_S)
                except queue.Empty:
                    message = None
                if message is not None and message[1] in workers:
                    kind, wid, payload, *rest = message
                    state = workers[wid]
                    if kind == "started":
                        state.current = next(p for p in state.assigned if p.key == payload)
                        state.started_at = time.monotonic()
                        ledger.started(payload)
                    elif kind in ("record", "failed"):
                        finished, state.current = state.current, None
                        state.assigned.remove(finished)
                        if kind == "record":
                            yield payload
                        elif (gap := ledger.failed(finished, rest[0])) is not None:
                            yield gap
                    elif kind == "idle":
                        state.busy = False
                for wid in list(workers):
                    state = workers[wid]
                    overdue = state.busy and time.monotonic() - state.started_at > self.timeout_s
                    if not (overdue or (state.busy and not state.process.is_alive())):
                        continue
                    state.process.kill()
                    state.process.join(timeout=10)
                    del workers[wid]
                    reason = (
                        f"episode timed out after {self.timeout_s:.0f}s"
                        if overdue
                        else f"worker process died (exit code {state.process.exitcode})"
                    )
                    # The episode in flight is charged; a worker that dies before starting one charges its
                    # first, so a worker that cannot start at all ends in gaps instead of respawning forever.
                    victim = state.current
                    if victim is None and state.assigned:
                        victim = state.assigned[0]
                        ledger.started(victim.key)
                    if victim is not None:
                        state.assigned.remove(victim)
                        if (gap := ledger.failed(victim, reason)) is not None:
                            yield gap
                    ledger.give_back(state.assigned)
                    if ledger:
                        spawn()
        finally:
            for state in workers.values():
                state.inbox.put(None)
            for state in workers.values():
                state.process.join(timeout=30)
                if state.process.is_alive():
                    state.process.kill()
