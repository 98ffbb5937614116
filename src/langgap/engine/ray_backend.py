"""Scheduling episodes on a Ray cluster: one `EpisodeRunner` per actor, results back to the driver's store.

The driver keeps the same ledger as the local backend: actors get the episodes of one task at a
time (so each actor reuses its environment), one episode in flight per actor. An episode whose
actor dies (its process or its node killed) or runs past the timeout is retried on a fresh actor;
after `max_attempts` it becomes a gap. The records, keys and provenance are those of every other
backend, so `--resume` and `langgap report` do not care which backend produced a run.
"""

from __future__ import annotations

import os
import time
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field, replace

from langgap.engine.plan import PlannedEpisode
from langgap.engine.runner import EpisodeFailure, EpisodeRunner, RunnerSetup
from langgap.engine.scheduling import Ledger
from langgap.engine.shared_policy import start_server
from langgap.errors import DependencyNotInstalled, LangGapError
from langgap.records import EpisodeRecord

_POLL_S = 0.5


def import_ray():
    try:
        import ray
    except ImportError:
        raise DependencyNotInstalled("the Ray backend needs Ray: pip install 'langgap[ray]'") from None
    return ray


class RunnerActor:
    """The body of a Ray actor: an `EpisodeRunner` that lives as long as the actor."""

    def __init__(self, setup: RunnerSetup, worker: int):
        self.runner = EpisodeRunner(setup, worker=worker)

    def pid(self) -> int:
        return os.getpid()

    def run(self, planned: PlannedEpisode, attempt: int) -> EpisodeRecord:
        return self.runner.run(planned, attempt)

    def close(self) -> None:
        self.runner.close()


@dataclass(frozen=True)
class SharedPolicyOptions:
    """One policy actor shared by all environment actors, batching their queries."""

    max_batch: int = 8
    max_wait_ms: float = 5.0
    gpus: float = 0.0


@dataclass
class _Actor:
    handle: object
    assigned: deque[PlannedEpisode] = field(default_factory=deque)
    current: PlannedEpisode | None = None
    ref: object = None
    started_at: float = 0.0


class RayBackend:
    """Episodes on Ray actors (`address=None` starts a local Ray instance with `workers` CPUs)."""

    def __init__(
        self,
        workers: int,
        *,
        address: str | None = None,
        timeout_s: float = 900.0,
        max_attempts: int = 3,
        shared_policy: SharedPolicyOptions | None = None,
    ):
        self.workers = max(1, workers)
        self.address = address
        self.timeout_s = timeout_s
        self.max_attempts = max_attempts
        self.shared_policy = shared_policy
        self.last_server_stats: dict = {}
        import_ray()

    def _connect(self, ray) -> bool:
        """Connect to (or start) Ray; returns whether this call started it (and so must shut it down)."""
        if ray.is_initialized():
            return False
        options = dict(include_dashboard=False, log_to_driver=False, configure_logging=False)
        try:
            if self.address:
                ray.init(address=self.address, **options)
            else:
                ray.init(num_cpus=self.workers, **options)
        except ConnectionError as exc:
            raise LangGapError(f"cannot reach the Ray cluster at {self.address}: {exc}") from None
        return True

    def run(self, plan: list[PlannedEpisode], setup: RunnerSetup) -> Iterator[EpisodeRecord]:
        ray = import_ray()
        from ray.exceptions import GetTimeoutError, RayActorError, RayTaskError

        started_ray = self._connect(ray)
        server = None
        if self.shared_policy is not None:
            options = self.shared_policy
            server = start_server(
                ray,
                setup.policy,
                setup.policy_args,
                max_batch=options.max_batch,
                max_wait_ms=options.max_wait_ms,
                num_gpus=options.gpus,
            )
            setup = replace(setup, policy_server=server)
        remote = ray.remote(num_cpus=1, max_restarts=0, max_task_retries=0)(RunnerActor)
        ledger = Ledger(plan, self.workers, setup, self.max_attempts)
        actors: list[_Actor] = []
        next_id = 0

        def spawn() -> None:
            nonlocal next_id
            actors.append(_Actor(remote.remote(setup, next_id)))
            next_id += 1

        def submit(actor: _Actor) -> None:
            actor.current = actor.assigned.popleft()
            actor.ref = actor.handle.run.remote(actor.current, ledger.started(actor.current.key))
            actor.started_at = time.monotonic()

        def retire(actor: _Actor, reason: str) -> Iterator[EpisodeRecord]:
            """Drop a dead or stuck actor: its episode is charged, the rest of its unit goes back."""
            ray.kill(actor.handle, no_restart=True)
            actors.remove(actor)
            if actor.current is not None and (gap := ledger.failed(actor.current, reason)) is not None:
                yield gap
            ledger.give_back(actor.assigned)
            if ledger:
                spawn()

        for _ in range(min(self.workers, len(ledger.units))):
            spawn()
        try:
            while ledger or any(a.current is not None or a.assigned for a in actors):
                for actor in actors:
                    if actor.current is None and not actor.assigned and ledger:
                        actor.assigned = ledger.take()
                    if actor.current is None and actor.assigned:
                        submit(actor)
                refs = [a.ref for a in actors if a.current is not None]
                ready, _ = ray.wait(refs, num_returns=1, timeout=_POLL_S) if refs else ([], [])
                for ref in ready:
                    actor = next(a for a in actors if a.ref is ref)
                    try:
                        record = ray.get(ref, timeout=60)
                    except RayTaskError as exc:
                        cause = exc.cause if isinstance(exc.cause, EpisodeFailure) else exc
                        failed, actor.current = actor.current, None
                        if (gap := ledger.failed(failed, str(cause).strip().splitlines()[-1])) is not None:
                            yield gap
                    except (RayActorError, GetTimeoutError) as exc:
                        yield from retire(actor, f"Ray actor died: {type(exc).__name__}")
                    else:
                        actor.current = None
                        yield record
                for actor in [a for a in actors if a.current is not None]:
                    if time.monotonic() - actor.started_at > self.timeout_s:
                        yield from retire(actor, f"episode timed out after {self.timeout_s:.0f}s")
        finally:
            for actor in actors:
                ray.kill(actor.handle, no_restart=True)
            if server is not None:
                self.last_server_stats = ray.get(server.stats.remote())
                ray.kill(server, no_restart=True)
            if started_ray:
                ray.shutdown()
