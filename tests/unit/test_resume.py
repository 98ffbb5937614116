"""What a resumed run still runs (`still_to_run`): every planned key the store does not hold as judged, the seed
included, so a run grown by `--repeats` (with `--extend`) runs its new repeats and stores every episode once."""

from __future__ import annotations

import dataclasses

from langgap.engine.evaluate import plan_of, resolve_run, still_to_run
from langgap.engine.plan import REPEAT_STRIDE
from langgap.engine.spec import RunSpec
from langgap.records import EpisodeKey, EpisodeRecord, Status
from langgap.store import RunStore
from langgap.vocabulary import Outcome
from tests.support.reports import SOURCE, episode

TASKS = "spatial/s0/black-bowl-1-on-plate,spatial/s0/ramekin-on-plate"


def _spec(repeats: int) -> RunSpec:
    return RunSpec.create("noop", tasks=TASKS, episodes=2, conditions=("given", "empty"), repeats=repeats)


def _stored(key: EpisodeKey, *, gap: bool = False) -> EpisodeRecord:
    """A stored episode of `key` (judged, or a gap)."""
    record = episode(SOURCE, key.init_index, gap=gap)
    return dataclasses.replace(record, task_id=key.task_id, seed=key.seed, condition=key.condition)


def test_a_run_grown_by_repeats_runs_the_new_seeds_and_the_gaps_and_stores_each_episode_once(tmp_path):
    first = plan_of(resolve_run(_spec(repeats=1), tmp_path / "run"))
    with RunStore.create(tmp_path / "run", {"spec": _spec(repeats=1).to_dict()}) as store:
        assert still_to_run(first, store.done_keys()) == first  # a new run runs its whole plan
        gap = first[3].key
        for planned in first:
            store.write(_stored(planned.key, gap=planned.key == gap))
        assert still_to_run(first, store.done_keys()) == [first[3]]  # a resume runs its gap again

        grown = plan_of(resolve_run(_spec(repeats=2), tmp_path / "run"))
        assert len(grown) == 2 * len(first) == 16
        todo = still_to_run(grown, store.done_keys())
        new = [p for p in grown if p.key.seed >= REPEAT_STRIDE]
        # Each new repeat shares its task, init state and condition with a stored one: only its seed tells it apart.
        assert {dataclasses.replace(p.key, seed=p.key.seed - REPEAT_STRIDE) for p in new} == {p.key for p in first}
        assert todo == [p for p in grown if p in new or p.key == gap]  # the plan's order
        for planned in todo:
            store.write(_stored(planned.key))
        stored = [r.key for r in store.records()]
        assert len(stored) == len(set(stored)) == len(grown) and set(stored) == {p.key for p in grown}
        assert all(r.status == Status.DONE and r.outcome != Outcome.GAP for r in store.records())
        assert still_to_run(grown, store.done_keys()) == []
