"""Which episodes `--video` films."""

from __future__ import annotations

import dataclasses

import pytest

from langgap.engine.filming import VideoSelection, replay_matches
from langgap.errors import LangGapError
from langgap.vocabulary import Outcome
from tests.support.reports import SOURCE, episode

TASKS = ("spatial/s0/ramekin-on-plate", "spatial/s0/bowl-on-stove")
_ENDS = {  # outcome -> how an episode of an extended task ends in it
    Outcome.SUCCESS: {"success": True},
    Outcome.DID_SOURCE_TASK: {"reached": {SOURCE: 5}},
    Outcome.NO_GOAL_REACHED: {},
}


def _records(outcomes: dict[str, list[Outcome]]):
    """Judged records of each task, init states 0.. ending in the given outcomes."""
    records = [
        episode(task, init, **_ENDS[outcome])
        for task, per_init in outcomes.items()
        for init, outcome in enumerate(per_init)
    ]
    assert [r.outcome for r in records] == [o for per_init in outcomes.values() for o in per_init]
    return records


@pytest.mark.parametrize(
    ("text", "selection"),
    [
        ("", VideoSelection()),
        ("3", VideoSelection("first", 3)),
        ("first:3", VideoSelection("first", 3)),
        ("per-outcome:2", VideoSelection("per-outcome", 2)),
    ],
)
def test_selections_parse(text, selection):
    assert VideoSelection.parse(text) == selection
    assert bool(selection) == (selection.count > 0)


@pytest.mark.parametrize("text", ["every:2", "per-outcome", "first:-1", "two", "per-outcome:1:x"])
def test_bad_selections_are_refused(text):
    with pytest.raises(LangGapError, match=f"^video (takes .*|must film at least 0 episodes), got '{text}'$"):
        VideoSelection.parse(text)


def test_first_films_the_first_planned_episodes_while_they_run():
    records = _records({TASKS[0]: [Outcome.SUCCESS] * 3})
    plan = [r.key for r in records]
    selection = VideoSelection("first", 2)
    assert selection.filmed_while_running(plan) == set(plan[:2])
    assert selection.choose(plan, records) == plan[:2]


def test_per_outcome_films_up_to_n_of_each_task_condition_and_outcome_in_plan_order():
    did, none, ok = Outcome.DID_SOURCE_TASK, Outcome.NO_GOAL_REACHED, Outcome.SUCCESS
    records = _records({TASKS[0]: [ok, did, did, none, did], TASKS[1]: [did, did]})
    records.append(dataclasses.replace(records[1], condition="empty"))
    plan = [r.key for r in records]
    selection = VideoSelection("per-outcome", 2)
    assert selection.filmed_while_running(plan) == set()  # outcomes are known only once judged
    chosen = selection.choose(plan, records)
    assert chosen == [plan[i] for i in (0, 1, 2, 3, 5, 6, 7)]
    gap = dataclasses.replace(records[0], status="gap", outcome=Outcome.GAP)
    assert plan[0] not in selection.choose(plan, [gap, *records[1:]])  # gaps have nothing to show


def test_a_replay_matches_only_when_it_ends_as_the_stored_episode():
    (stored,) = _records({TASKS[0]: [Outcome.DID_SOURCE_TASK]})
    assert replay_matches(stored, dataclasses.replace(stored, wall_time_s=9.0, video="videos/x.webm"))
    for change in ({"steps": stored.steps + 1}, {"outcome": Outcome.NO_GOAL_REACHED}, {"reached": {}},
                   {"t0_hash": "other"}, {"status": "gap"}):  # fmt: skip
        assert not replay_matches(stored, dataclasses.replace(stored, **change))
