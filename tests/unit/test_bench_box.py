"""bench_box's "records identical" verdict: runs of one plan compare identical exactly when every episode ended
alike (whatever their worker count or `replan` changed in the measured fields), and none is a gap."""

from __future__ import annotations

import dataclasses

import pytest

from bench.bench_box import compared, same_records
from langgap.vocabulary import Outcome
from tests.support.reports import SOURCE, TASKS, episode

RAMEKIN, STOVE = "spatial/s0/ramekin-on-plate", "spatial/s0/bowl-on-stove"


def _run() -> list:
    """A small run: every task of tests.support.reports on init states 0 and 1, some successful, some that did
    their source task, as a replay of one plan stores them."""
    records = []
    for task_id in TASKS:
        for k in (0, 1):
            reached = {SOURCE: 40, STOVE: 55} if task_id != SOURCE and k == 1 else {}
            records.append(episode(task_id, k, success=task_id == SOURCE, reached=reached))
    return records


def _identical(records: list, reference: list) -> bool:
    return same_records(compared(records), compared(reference)["identity"])


def _changed(records: list, episode_of: tuple[str, int], **changes) -> list:
    """`records` with the episode of (task, init state) `episode_of` changed by `changes`."""
    return [dataclasses.replace(r, **changes) if (r.task_id, r.init_index) == episode_of else r for r in records]


def test_runs_that_differ_only_in_what_the_bench_varies_or_measures_are_identical():
    reference = _run()
    assert _identical(reference, reference)
    # Another worker count and replan: other calls, config hash, workers, times, and records in another order.
    again = [
        dataclasses.replace(r, policy_calls=r.steps // 5, policy_config_hash="other", worker=3, wall_time_s=9.5,
                            finished_at="2026-01-01T00:00:00+00:00", reached=dict(reversed(list(r.reached.items()))))
        for r in reversed(reference)
    ]  # fmt: skip
    assert _identical(again, reference)


@pytest.mark.parametrize(
    "changes",
    [
        {"success": True},
        {"outcome": Outcome.WRONG_ORDER},  # it did its source task
        {"steps": 11},
        {"t0_hash": "another start"},
        {"reached": {SOURCE: 41, STOVE: 55}},  # the source's goal one step later
        {"reached": {SOURCE: 40}},  # one goal fewer
        {"reached": {SOURCE: 40, STOVE: 55, RAMEKIN: 60}},  # one more
        {"reached": {}},  # none
    ],
    ids=lambda changes: ",".join(changes),
)
def test_a_run_whose_episode_ended_otherwise_in_any_compared_field_differs(changes):
    reference = _run()
    changed = _changed(reference, (RAMEKIN, 1), **changes)
    assert changed != reference
    assert not _identical(changed, reference) and not _identical(reference, changed)


def test_a_run_with_an_episode_missing_more_or_another_differs():
    reference = _run()
    assert not _identical(reference[1:], reference)
    assert not _identical([*reference, episode(RAMEKIN, 2)], reference)
    assert not _identical(_changed(reference, (RAMEKIN, 1), init_index=2), reference)
    assert not _identical(_changed(reference, (RAMEKIN, 1), task_id=SOURCE), reference)


def test_a_run_with_a_gap_differs_even_from_its_own_identity():
    gapped = _changed(_run(), (RAMEKIN, 1), status="gap")
    assert compared(gapped)["gaps"] == 1
    assert not same_records(compared(gapped), compared(gapped)["identity"])
