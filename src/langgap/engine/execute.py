"""The executor: every kind of work item through the one scheduler, on the backend the options name.

`evaluate` opens its pool before the run's store (so options a backend cannot satisfy fail before a
run directory exists) and calls `scheduled`; every other command's work goes through `execute`, which
opens the pool itself. Both show the same progress bar (`with_progress`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Iterator
from typing import TypeVar

from langgap.engine.pools import WorkerPool, make_pool
from langgap.engine.runner import RunnerSetup
from langgap.engine.scheduler import GapFactory, make_units, schedule
from langgap.engine.spec import ExecutionOptions
from langgap.engine.work import WorkItem, refuse_gap

Item = TypeVar("Item", bound=WorkItem)
Result = TypeVar("Result")


def scheduled(
    items: list[Item], pool: WorkerPool, options: ExecutionOptions, make_gap: GapFactory[Item, Result]
) -> Iterator[Result]:
    """`items` scheduled on `pool` with the retries, timeouts and fail-fast rule `options` give; when fewer workers
    can start than `options.workers` asks for, a `note:` line on stderr says so (`fewer_workers_note`)."""
    workers = max(1, options.workers)
    if note := fewer_workers_note(items, workers):
        print(note, file=sys.stderr, flush=True)
    return schedule(
        items,
        pool,
        workers=workers,
        make_gap=make_gap,
        max_attempts=options.max_attempts,
        max_failure_streak=options.max_failure_streak,
        timeout_s=options.episode_timeout_s,
    )


def fewer_workers_note(items: list[WorkItem], workers: int) -> str | None:
    """The line that says fewer than `workers` workers start, and why: never more than the parts the work splits
    into (`make_units`), one per item at most; None when every worker asked for starts."""
    parts = len(make_units(items, workers))
    if not items or parts >= workers:
        return None
    kind = items[0].kind
    why = (
        f"there are {len(items)} {kind}s to run"
        if parts == len(items)
        else f"the {len(items)} {kind}s to run make {parts} parts (a task's {kind}s run in order on one worker)"
    )
    return f"note: {parts} workers start, not {workers}: {why}"


def execute(
    items: list[Item],
    setup: RunnerSetup,
    options: ExecutionOptions,
    *,
    unit: str,
    make_gap: GapFactory[Item, Result] = refuse_gap,
    describe: Callable[[Result], str] | None = None,
) -> Iterator[Result]:
    """Run `items` on a pool of backend `options.backend` (opened here, closed when the results end or
    their reader stops); yields each result as its item ends, in no fixed order. `unit` and `describe`
    (a result's few words) label the progress bar. No items: no pool is opened (no Ray cluster joined)."""
    if not items:
        return
    pool = make_pool(setup, options)
    try:
        results = scheduled(items, pool, options, make_gap)
        yield from with_progress(results, len(items), unit=unit, enabled=options.progress, describe=describe)
    finally:
        pool.close()


def with_progress(
    results: Iterable[Result],
    total: int,
    *,
    unit: str,
    enabled: bool,
    describe: Callable[[Result], str] | None = None,
    label: str | None = None,
) -> Iterator[Result]:
    """`results` as they come, with a progress bar (ETA, and `describe` of the latest result) on stderr, named
    `label` when the command shows more than one."""
    if not (enabled and total):
        yield from results
        return
    from tqdm import tqdm

    bar = tqdm(
        total=total,
        unit=unit,
        desc=label,
        file=sys.stderr,
        dynamic_ncols=True,
        mininterval=0.5 if sys.stderr.isatty() else 30.0,
    )
    try:
        for result in results:
            yield result
            if describe is not None:
                bar.set_postfix_str(describe(result), refresh=False)
            bar.update(1)
    finally:
        bar.close()
