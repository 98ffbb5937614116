"""What an episode achieved, from the scene goals that became true during it."""

from __future__ import annotations

from dataclasses import fields

import pytest

from langgap.records import COLUMNS, KEY_COLUMNS, EpisodeKey, EpisodeRecord, Outcome, achieved, classify

SOURCE = "spatial/s0/bowl-on-plate"
TASK = "spatial/s0/ramekin-on-plate"


@pytest.mark.parametrize(
    ("task", "kind", "success", "reached", "outcome"),
    [
        (TASK, "extended", True, {TASK: 40, SOURCE: 10}, Outcome.SUCCESS),
        (TASK, "extended", False, {SOURCE: 10}, Outcome.DID_SOURCE_TASK),
        (TASK, "extended", False, {"spatial/s0/bowl-on-stove": 3, SOURCE: 10}, Outcome.DID_SOURCE_TASK),
        (TASK, "extended", False, {"spatial/s0/bowl-on-stove": 3}, Outcome.DID_OTHER_TASK),
        (TASK, "extended", False, {}, Outcome.NO_GOAL_REACHED),
        # An original task's source is itself: doing another scene task is "other", never "source".
        (SOURCE, "original", False, {TASK: 5}, Outcome.DID_OTHER_TASK),
        (SOURCE, "original", False, {}, Outcome.NO_GOAL_REACHED),
    ],
)
def test_classify(task, kind, success, reached, outcome):
    assert classify(task, kind, SOURCE, success, reached) is outcome


def _record(**changes) -> EpisodeRecord:
    base = dict(
        task_id=TASK,
        init_index=0,
        seed=0,
        condition="given",
        status="done",
        success=False,
        outcome="",
        failure_kind=None,
        error=None,
        steps=1,
        policy_calls=1,
        instruction="",
        instruction_sha256="",
        t0_hash="",
    )
    return EpisodeRecord(**{**base, **changes})


def test_achieved_is_the_own_task_else_the_earliest_goal_then_name():
    assert achieved(_record(success=True, reached={SOURCE: 1})) == TASK
    assert achieved(_record(reached={SOURCE: 9, "b": 4, "a": 4})) == "a"
    assert achieved(_record()) == "none"


def test_gaps_are_not_judged_and_the_key_names_the_episode():
    assert _record().judged and not _record(status="gap").judged
    assert _record(condition="empty").key == EpisodeKey(TASK, 0, 0, "empty")


def test_the_stored_columns_are_the_record_fields():
    assert [c.name for c in COLUMNS] == [f.name for f in fields(EpisodeRecord)]
    assert KEY_COLUMNS == ("task_id", "init_index", "seed", "condition")
