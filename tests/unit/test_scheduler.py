"""The one scheduling loop, on a scripted worker pool and a fake clock."""

from __future__ import annotations

import dataclasses
from collections import deque

import pytest

from langgap.engine.execute import scheduled
from langgap.engine.plan import PlannedEpisode
from langgap.engine.pools import ItemDone, ItemFailed, WorkerLost
from langgap.engine.scheduler import RunStopped, make_units, schedule
from langgap.engine.spec import ExecutionOptions
from langgap.engine.work import AttemptsExhausted, Job, refuse_gap
from langgap.records import EpisodeKey, EpisodeRecord, Status


def plan(tasks=("s0/a", "s0/b", "s1/c"), episodes=2) -> list[PlannedEpisode]:
    return [
        PlannedEpisode(EpisodeKey(t, k, k), f"do {t}", scene=t.split("/")[0], watched=(t,))
        for t in tasks
        for k in range(episodes)
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
            self._events.append(ItemDone(worker, record(planned, worker, attempt)))
        elif outcome.startswith("fail:"):
            self._events.append(ItemFailed(worker, outcome[5:]))
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


def test_a_success_between_failures_resets_the_streak():
    episodes = plan(tasks=("s0/a",), episodes=6)  # one worker: units k0-k2, then k3-k5
    keys = [p.key for p in episodes]

    def failing(*indices):
        return lambda p, attempt: "fail:down" if attempt == 1 and keys.index(p.key) in indices else "done"

    records = run(episodes, ScriptedPool(failing(0, 1, 3, 4)), workers=1)  # k2 and k5 succeed in between
    assert sorted(r.key for r in records) == keys and all(r.status == Status.DONE for r in records)
    assert {r.key: r.attempts for r in records} == {k: 2 if keys.index(k) in (0, 1, 3, 4) else 1 for k in keys}
    with pytest.raises(RunStopped):  # the same failures without a success in between stop the run
        run(episodes, ScriptedPool(failing(0, 1, 2)), workers=1)


def test_one_episode_failing_again_and_again_is_not_an_outage():
    (only,) = plan(tasks=("s0/a",), episodes=1)
    pool = ScriptedPool(lambda p, attempt: "fail:segfault in the renderer")
    (the_gap,) = run([only], pool, workers=1, max_attempts=5, max_failure_streak=2)
    assert [a for _, _, a in pool.submitted] == [1, 2, 3, 4, 5]
    assert (the_gap.status, the_gap.attempts, the_gap.error) == (Status.GAP, 5, "segfault in the renderer")


def test_a_single_attempt_makes_a_gap_at_the_first_failure():
    episodes = plan()
    pool = ScriptedPool(lambda p, attempt: "fail:boom" if p.key == episodes[3].key else "done")
    records = run(episodes, pool, max_attempts=1)
    assert [k for _, k, _ in pool.submitted].count(episodes[3].key) == 1
    assert [(r.key, r.status) for r in records if r.status == Status.GAP] == [(episodes[3].key, Status.GAP)]


def test_the_records_before_a_stop_are_yielded():
    episodes = plan()
    pool = ScriptedPool(lambda p, attempt: "done" if p.key in (episodes[0].key, episodes[1].key) else "fail:down")
    records = []
    with pytest.raises(RunStopped, match="3 episodes in a row failed with: down"):
        for r in schedule(
            episodes, pool, workers=1, make_gap=gap, max_attempts=3, max_failure_streak=3, timeout_s=None
        ):
            records.append(r)
    assert [r.key for r in records] == [episodes[0].key, episodes[1].key]


def test_a_lost_worker_gives_back_the_rest_of_its_unit():
    episodes = plan(tasks=("s0/a",), episodes=4)  # one worker: units k0-k1, k2-k3
    k0, k1, k2, k3 = (p.key for p in episodes)
    pool = ScriptedPool(lambda p, attempt: "lost" if p.key == k0 and attempt == 1 else "done")
    records = run(episodes, pool, workers=1)
    # the replacement (worker 1) first runs what worker 0 had not started, the charged episode last
    assert pool.submitted == [(0, k0, 1), (1, k1, 1), (1, k2, 1), (1, k3, 1), (1, k0, 2)]
    assert sorted(r.key for r in records) == [k0, k1, k2, k3] and pool.spawned == [0, 1]


def test_a_worker_lost_on_every_attempt_leaves_a_gap_with_its_reason():
    episodes = plan()
    doomed = episodes[1].key
    pool = ScriptedPool(lambda p, attempt: "lost" if p.key == doomed else "done")
    records = run(episodes, pool, max_failure_streak=10)
    (the_gap,) = [r for r in records if r.status == Status.GAP]
    assert (the_gap.key, the_gap.attempts, the_gap.error) == (doomed, 3, "worker process died (exit code 9)")
    # a replacement for each loss while work remains (the third loss was the last episode left)
    assert pool.spawned == [0, 1, 2, 3] and len(records) == len(episodes)


class LateReportingPool(ScriptedPool):
    """A killed worker's episode still reports afterwards (a race the scheduler must ignore)."""

    def __init__(self, script):
        super().__init__(script)
        self.running: dict[int, tuple[PlannedEpisode, int]] = {}

    def submit(self, worker, planned, attempt):
        self.running[worker] = (planned, attempt)
        super().submit(worker, planned, attempt)

    def kill(self, worker):
        super().kill(worker)
        planned, attempt = self.running[worker]
        self._events.append(ItemDone(worker, record(planned, worker, attempt)))


def test_a_timeout_kills_that_worker_replaces_it_and_ignores_what_it_says_later():
    now = [0.0]

    def clock():
        now[0] += 5.0
        return now[0]

    episodes = plan()
    stuck = episodes[0].key  # two workers, six units of one episode: worker 0 gets it first
    pool = LateReportingPool(lambda p, attempt: "hang" if p.key == stuck else "done")
    records = run(episodes, pool, clock=clock, timeout_s=12, max_failure_streak=10)
    # each stuck worker is killed, and replaced while work remains (the third attempt was the last episode)
    assert [(w, a) for w, k, a in pool.submitted if k == stuck] == [(0, 1), (2, 2), (1, 3)]
    assert pool.killed == [0, 2, 1] and pool.spawned == [0, 1, 2, 3]
    assert sorted(r.key for r in records) == sorted(p.key for p in episodes)  # the late reports were dropped
    (the_gap,) = [r for r in records if r.status == Status.GAP]
    assert (the_gap.key, the_gap.attempts, the_gap.error) == (stuck, 3, "episode timed out after 12s")


def test_no_timeout_without_a_limit():
    now = [0.0]

    def clock():
        now[0] += 1000.0
        return now[0]

    slow = ScriptedPool()
    run(plan(), slow, clock=clock, timeout_s=None)
    assert slow.killed == []


def test_units_group_a_scene_whatever_the_plan_order():
    episodes = plan(tasks=("s1/c", "s0/a", "s1/d", "s0/b"), episodes=2)
    units = make_units(episodes, workers=1)  # 4 tasks, 2 pieces wanted per worker: one unit per task
    assert [[(p.key.task_id, p.key.init_index) for p in u] for u in units] == [
        [("s0/a", 0), ("s0/a", 1)], [("s0/b", 0), ("s0/b", 1)], [("s1/c", 0), ("s1/c", 1)], [("s1/d", 0), ("s1/d", 1)]
    ]  # fmt: skip


def test_units_split_evenly_for_more_workers():
    units = make_units(plan(tasks=("s0/a", "s0/b"), episodes=5), workers=3)  # 2 tasks, 6 pieces wanted
    assert [[(p.key.task_id, p.key.init_index) for p in u] for u in units] == [
        [("s0/a", 0), ("s0/a", 1)], [("s0/a", 2), ("s0/a", 3)], [("s0/a", 4)],
        [("s0/b", 0), ("s0/b", 1)], [("s0/b", 2), ("s0/b", 3)], [("s0/b", 4)],
    ]  # fmt: skip
    assert [len(u) for u in make_units(plan(tasks=("s0/a", "s0/b", "s1/c", "s1/d"), episodes=3), workers=2)] == [3] * 4


def test_no_more_workers_than_units():
    pool = ScriptedPool()
    records = run(plan(tasks=("s0/a",), episodes=1), pool, workers=4)
    assert pool.spawned == [0] and len(records) == 1
    empty = ScriptedPool()
    assert run([], empty, workers=4) == [] and empty.spawned == []


def test_many_workers_and_mixed_trouble_still_give_one_record_per_episode():
    episodes = plan(tasks=("s0/a", "s0/b", "s1/c", "s2/d"), episodes=5)
    trouble = {0: "fail:x", 3: "lost", 7: "fail:y", 11: "lost", 15: "fail:z"}
    index = {p.key: n for n, p in enumerate(episodes)}
    pool = ScriptedPool(lambda p, attempt: trouble.get(index[p.key], "done") if attempt == 1 else "done")
    records = run(episodes, pool, workers=3)
    assert sorted(r.key for r in records) == sorted(index)
    assert {r.key: r.attempts for r in records} == {k: 2 if n in trouble else 1 for k, n in index.items()}
    assert len(pool.spawned) == 3 + 2 and not pool.closed


@dataclasses.dataclass(frozen=True)
class Probe(Job):
    """A work item of another kind than an episode, `size` episodes' worth of simulation."""

    kind = "probe"

    task_id: str
    weight: int = 1

    @property
    def size(self) -> int:
        return self.weight


class ProbePool(ScriptedPool):
    """Workers that report a probe's task id as its result, or never report (`hang`) the probes `script` says."""

    def submit(self, worker, item, attempt):
        self.submitted.append((worker, item.key, attempt))
        if self.script(item, attempt) == "done":
            self._events.append(ItemDone(worker, item.task_id))


def test_work_of_another_kind_gets_the_same_scheduling_with_a_timeout_scaled_by_its_size():
    now = [0.0]

    def clock():
        now[0] += 5.0
        return now[0]

    slow, heavy = Probe("s0/slow"), Probe("s1/heavy", weight=10)
    pool = ProbePool(lambda item, attempt: "hang" if attempt == 1 else "done")
    killed_at = {}
    pool.kill = lambda worker: killed_at.setdefault(worker, now[0])
    results = run([slow, heavy], pool, clock=clock, timeout_s=12, make_gap=refuse_gap)
    assert sorted(results) == ["s0/slow", "s1/heavy"]  # each retried once, on a new worker
    first = {k.task_id: w for w, k, a in pool.submitted if a == 1}
    # The size-1 probe was killed past 12 s; the size-10 one had 120 s.
    assert killed_at[first["s0/slow"]] < 30 and 120 < killed_at[first["s1/heavy"]] < 140


def test_work_that_has_no_gap_fails_the_command_once_its_attempts_are_spent():
    pool = ProbePool(lambda item, attempt: "never")
    pool.submit = lambda worker, item, attempt: pool._events.append(ItemFailed(worker, "GL context lost"))
    with pytest.raises(AttemptsExhausted, match=r"^probe s0/a failed 2 time\(s\): GL context lost$") as info:
        run([Probe("s0/a")], pool, make_gap=refuse_gap, max_attempts=2)
    assert info.value.exit_code == 4


@pytest.mark.parametrize(
    ("episodes", "workers", "note"),
    [
        (plan(), 999, "note: 6 workers start, not 999: there are 6 episodes to run\n"),
        (plan(tasks=[f"s{i}/t" for i in range(5)], episodes=1) + plan(tasks=("s9/u",), episodes=5), 10,
         "note: 8 workers start, not 10: the 10 episodes to run make 8 parts (a task's episodes run in order on one "
         "worker)\n"),
        (plan(), 6, ""),
        (plan(), 0, ""),  # this process runs them
    ],
)  # fmt: skip
def test_asking_for_more_workers_than_can_start_says_how_many_do(episodes, workers, note, capsys):
    pool = ScriptedPool()
    records = list(scheduled(episodes, pool, ExecutionOptions(workers=workers), gap))
    assert capsys.readouterr().err == note and len(records) == len(episodes)
    assert len(pool.spawned) == (int(note.split()[1]) if note else max(1, workers))
