"""The one scheduling loop, on a scripted worker pool and a fake clock."""

from __future__ import annotations

import dataclasses
from collections import deque

import pytest

from langgap.engine.plan import PlannedEpisode
from langgap.engine.pools import EpisodeDone, EpisodeFailed, WorkerLost
from langgap.engine.scheduler import RunStopped, make_units, schedule
from langgap.records import EpisodeKey, EpisodeRecord, Status


def plan(tasks=("s0/a", "s0/b", "s1/c"), episodes=2) -> list[PlannedEpisode]:
    return [
        PlannedEpisode(EpisodeKey(t, k, k), f"do {t}", scene=t.split("/")[0]) for t in tasks for k in range(episodes)
    ]


def record(planned: PlannedEpisode, worker: int, attempt: int, status=Status.DONE, error=None) -> EpisodeRecord:
    return EpisodeRecord(
        **dataclasses.asdict(planned.key),
        status=status, success=False, outcome="", failure_kind=None, error=error, steps=1, policy_calls=1,
        instruction=planned.instruction, instruction_sha256="", t0_hash="", worker=worker, attempts=attempt,
    )  # fmt: skip


def gap(planned: PlannedEpisode, error: str, attempts: int) -> EpisodeRecord:
    return record(planned, -1, attempts, Status.GAP, error)


class ScriptedPool:
    """Workers whose episodes end as `script(planned, attempt)` says: "done", "fail:<cause>", "lost" or "hang"."""

    def __init__(self, script=lambda planned, attempt: "done"):
        self.script = script
        self.spawned: list[int] = []
        self.killed: list[int] = []
        self.submitted: list[tuple[int, EpisodeKey, int]] = []
        self.closed = False
        self._events: deque = deque()

    def spawn(self) -> int:
        self.spawned.append(len(self.spawned))
        return self.spawned[-1]

    def submit(self, worker, planned, attempt):
        self.submitted.append((worker, planned.key, attempt))
        outcome = self.script(planned, attempt)
        if outcome == "done":
            self._events.append(EpisodeDone(worker, record(planned, worker, attempt)))
        elif outcome.startswith("fail:"):
            self._events.append(EpisodeFailed(worker, outcome[5:]))
        elif outcome == "lost":
            self._events.append(WorkerLost(worker, "worker process died (exit code 9)"))

    def poll(self, timeout):
        events, self._events = list(self._events), deque()
        return events

    def kill(self, worker):
        self.killed.append(worker)

    def close(self):
        self.closed = True


def run(episodes, pool, clock=None, **options):
    kwargs = dict(workers=2, make_gap=gap, max_attempts=3, max_failure_streak=3, timeout_s=None) | options
    if clock is not None:
        kwargs["clock"] = clock
    return list(schedule(episodes, pool, **kwargs))


def test_every_planned_episode_yields_one_record_and_the_pool_stays_open():
    episodes, pool = plan(), ScriptedPool()
    records = run(episodes, pool)
    assert sorted(r.key for r in records) == sorted(p.key for p in episodes)
    assert pool.spawned == [0, 1] and not pool.closed  # whoever made the pool closes it


def test_units_keep_a_scene_together_and_split_to_keep_workers_busy():
    units = make_units(plan(episodes=4), workers=1)
    assert [[p.key.task_id for p in u] for u in units] == [["s0/a"] * 4, ["s0/b"] * 4, ["s1/c"] * 4]
    units = make_units(plan(tasks=("s0/a",), episodes=4), workers=2)
    assert [len(u) for u in units] == [1, 1, 1, 1]


def test_a_failure_is_retried_after_the_other_episodes_then_becomes_a_gap():
    flaky = plan()[0].key
    pool = ScriptedPool(lambda p, attempt: "fail:boom" if p.key == flaky else "done")
    records = run(plan(), pool, workers=1, max_failure_streak=10)
    attempts = [(k, a) for _, k, a in pool.submitted if k == flaky]
    assert attempts == [(flaky, 1), (flaky, 2), (flaky, 3)]
    order = [k for _, k, _ in pool.submitted]
    assert order.index(plan()[1].key) < order.index(flaky, 1)  # the retry went to the back of the queue
    (the_gap,) = [r for r in records if r.status == Status.GAP]
    assert (the_gap.key, the_gap.attempts, the_gap.error) == (flaky, 3, "boom")
    assert len(records) == len(plan())


def test_a_lost_worker_is_replaced_and_its_episode_charged():
    lost_once = plan()[2].key
    pool = ScriptedPool(lambda p, attempt: "lost" if p.key == lost_once and attempt == 1 else "done")
    records = run(plan(), pool)
    assert len(pool.spawned) == 3  # the replacement
    retried = next(r for r in records if r.key == lost_once)
    assert retried.status == Status.DONE and retried.attempts == 2
    assert len(records) == len(plan())


def test_an_episode_past_its_timeout_is_killed_and_retried():
    now = [0.0]

    def clock():
        now[0] += 5.0
        return now[0]

    stuck = plan()[0].key
    pool = ScriptedPool(lambda p, attempt: "hang" if p.key == stuck and attempt == 1 else "done")
    records = run(plan(), pool, clock=clock, timeout_s=12)
    assert pool.killed and next(r for r in records if r.key == stuck).attempts == 2


def test_one_cause_on_three_different_episodes_in_a_row_stops_the_run():
    pool = ScriptedPool(lambda p, attempt: "fail:no policy server at 127.0.0.1:8000")
    with pytest.raises(RunStopped, match="3 episodes in a row failed with: no policy server at 127.0.0.1:8000") as info:
        run(plan(), pool, workers=1)
    assert info.value.exit_code == 4 and len(pool.submitted) == 3  # three episodes, one attempt each


@pytest.mark.parametrize(
    "script",
    [
        # one task keeps crashing while the others finish: only its attempts are spent
        lambda p, attempt: "fail:crash" if p.key.task_id == "s0/a" else "done",
        # failures with different causes are not one outage
        lambda p, attempt: f"fail:cause {p.key.task_id}" if attempt == 1 else "done",
    ],
)
def test_failures_that_are_not_one_outage_do_not_stop_the_run(script):
    records = run(plan(), ScriptedPool(script), workers=1)
    assert len(records) == len(plan())
