"""The pool of local worker processes.

Workers are started with `spawn` (no simulator or GL state crosses a fork), build their environment
lazily, keep it while consecutive episodes share a scene, and exit on their own if the scheduling
process dies (so a `kill -9` of `langgap eval` leaves no orphan simulating). With `--shared-policy`
the workers hold no policy: one policy process serves them all, batching their queries
(`langgap.engine.pools.policy_process`); it is started with the pool and stopped with it.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import queue
from dataclasses import replace
from typing import TYPE_CHECKING

from langgap.engine.pools import Event, ItemDone, ItemFailed, WorkerLost
from langgap.engine.pools.lifetime import exit_with_parent
from langgap.engine.pools.policy_process import PolicyProcess
from langgap.engine.runner import RunnerSetup, WorkFailure, WorkRunner
from langgap.engine.work import WorkItem

if TYPE_CHECKING:
    from langgap.engine.spec import ExecutionOptions


def worker_main(worker: int, setup: RunnerSetup, inbox, outbox, parent_pid: int) -> None:
    """Entry point of a worker process: run the work items it is sent until it receives None."""
    exit_with_parent(parent_pid)
    runner = WorkRunner(setup, worker=worker)
    try:
        while (message := inbox.get()) is not None:
            item, attempt = message
            try:
                outbox.put(ItemDone(worker, runner.run(item, attempt)))
            except WorkFailure as exc:
                outbox.put(ItemFailed(worker, str(exc)))
    finally:
        runner.close()


class ProcessPool:
    """Worker processes on this machine, one work item at a time each (and the shared policy's process)."""

    def __init__(self, setup: RunnerSetup, options: ExecutionOptions):
        self.server: PolicyProcess | None = None
        self.server_stats: dict = {}  # the shared policy's counters, read when the pool closes
        if options.shared_policy:
            self.server = PolicyProcess(
                setup.policy, setup.policy_args, max_batch=options.batch_limit, max_wait_ms=options.batch_wait_ms
            )
            setup = replace(setup, policy_server=self.server.address)
        self.setup = setup
        self._context = mp.get_context("spawn")
        self._outbox = self._context.Queue()
        self._workers: dict[int, tuple[mp.Process, object]] = {}  # id -> (process, inbox)
        self._next_id = 0

    def spawn(self) -> int:
        worker, self._next_id = self._next_id, self._next_id + 1
        inbox = self._context.Queue()
        process = self._context.Process(
            target=worker_main,
            args=(worker, self.setup, inbox, self._outbox, os.getpid()),
            daemon=True,
            name=f"langgap-worker-{worker}",
        )
        process.start()
        self._workers[worker] = (process, inbox)
        return worker

    def submit(self, worker: int, item: WorkItem, attempt: int) -> None:
        self._workers[worker][1].put((item, attempt))

    def poll(self, timeout: float) -> list[Event]:
        # Deaths are read before the queue is drained: whatever a dead worker sent before it died is
        # already in the pipe, so its last result is never mistaken for a loss.
        dead = [w for w, (process, _) in self._workers.items() if not process.is_alive()]
        events: list[Event] = []
        try:
            events.append(self._outbox.get(timeout=timeout))
            while True:
                events.append(self._outbox.get_nowait())
        except queue.Empty:
            pass
        for worker in dead:
            process, _ = self._workers.pop(worker)
            events.append(WorkerLost(worker, f"worker process died (exit code {process.exitcode})"))
        return events

    def kill(self, worker: int) -> None:
        process, _ = self._workers.pop(worker)
        process.kill()
        process.join(timeout=10)

    def close(self) -> None:
        for _, inbox in self._workers.values():
            inbox.put(None)
        for process, _ in self._workers.values():
            process.join(timeout=30)
            if process.is_alive():
                process.kill()
        self._workers.clear()
        if self.server is not None:
            self.server_stats = self.server.close()
            self.server = None
