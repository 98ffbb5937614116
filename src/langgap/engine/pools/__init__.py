"""Worker pools: where work items run. They only provide workers; `langgap.engine.scheduler` decides what runs.

A pool starts workers, hands one work item (`langgap.engine.work`) at a time to a worker, and reports
what happened as typed events. Retries, timeouts, respawns and gaps are the scheduler's, written once for all pools.

Backends by name (`--backend`): `local` (worker processes on this machine, or this process with
`--workers 0`) and `ray` (actors on a Ray cluster). Both can share one batching policy among their
workers (`--shared-policy`: a policy process, or a policy actor).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from langgap.errors import LangGapError

if TYPE_CHECKING:
    from langgap.catalog.catalog import Catalog
    from langgap.engine.runner import RunnerSetup
    from langgap.engine.spec import ExecutionOptions
    from langgap.engine.work import WorkItem


@dataclass(frozen=True)
class ItemDone:
    """A worker finished a work item (an episode: a success or a policy failure, the policy was judged)."""

    worker: int
    result: Any  # what the item's work returned (an episode's `EpisodeRecord`)


@dataclass(frozen=True)
class ItemFailed:
    """Infrastructure failed a work item on a worker that is still usable (its runner rebuilt its state)."""

    worker: int
    error: str


@dataclass(frozen=True)
class WorkerLost:
    """A worker is gone (its process or actor died); whatever it was running failed with it."""

    worker: int
    reason: str


Event = ItemDone | ItemFailed | WorkerLost


class WorkerPool(Protocol):
    """What the scheduler needs from a backend."""

    def spawn(self) -> int:
        """Start a worker; returns its id (never reused)."""
        ...

    def submit(self, worker: int, item: WorkItem, attempt: int) -> None:
        """Start `item` on an idle `worker`."""
        ...

    def poll(self, timeout: float) -> list[Event]:
        """Events since the last call, waiting up to `timeout` seconds for the first."""
        ...

    def kill(self, worker: int) -> None:
        """Stop a worker at once (an item past its timeout); no event follows for it."""
        ...

    def close(self) -> None:
        """Stop every worker and release the pool's resources."""
        ...


# (setup, options, the catalog `setup` names as this process loaded it: a runner in this process uses it)
PoolFactory = Callable[["RunnerSetup", "ExecutionOptions", "Catalog | None"], WorkerPool]


def _local(setup: RunnerSetup, options: ExecutionOptions, catalog: Catalog | None) -> WorkerPool:
    if options.workers == 0:
        from langgap.engine.pools.inprocess import InProcessPool

        return InProcessPool(setup, catalog)
    from langgap.engine.pools.processes import ProcessPool

    return ProcessPool(setup, options)


def _ray(setup: RunnerSetup, options: ExecutionOptions, _catalog: Catalog | None) -> WorkerPool:
    from langgap.engine.pools.ray import RayPool

    return RayPool(setup, options)


BACKENDS: dict[str, PoolFactory] = {"local": _local, "ray": _ray}


@contextlib.contextmanager
def backend_session(options: ExecutionOptions) -> Iterator[None]:
    """Keep the backend's connection open across several engine calls made inside (a validation's episodes,
    searches and settle probes start one local Ray instance, not one each); a no-op for `local`."""
    if options.backend != "ray":
        yield
        return
    from langgap.engine.pools.ray import ray_session

    with ray_session(options):
        yield


def make_pool(setup: RunnerSetup, options: ExecutionOptions, catalog: Catalog | None = None) -> WorkerPool:
    """The worker pool of backend `options.backend`. `catalog`: `setup.catalog` as this process loaded it, for a
    worker in this process (`--workers 0`); workers in other processes load it themselves."""
    if options.backend not in BACKENDS:
        raise LangGapError(f"unknown backend {options.backend!r} (known: {', '.join(sorted(BACKENDS))})")
    return BACKENDS[options.backend](setup, options, catalog)
