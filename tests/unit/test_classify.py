"""What an episode achieved, from the scene goals that became true during it."""

from __future__ import annotations

from dataclasses import fields

import pytest

from langgap.records import (
    COLUMNS,
    JUDGED_OUTCOMES,
    KEY_COLUMNS,
    EpisodeKey,
    EpisodeRecord,
    Outcome,
    Status,
    achieved,
    classify,
    record_dict,
)

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
        # ...even when its own goal (= its source's) held for a while: only extended tasks "do the source task"
        (SOURCE, "original", False, {SOURCE: 5}, Outcome.NO_GOAL_REACHED),
        (SOURCE, "original", False, {SOURCE: 5, TASK: 9}, Outcome.DID_OTHER_TASK),
        (SOURCE, "original", True, {SOURCE: 7}, Outcome.SUCCESS),
        # success decides even when nothing was recorded as reached
        (TASK, "extended", True, {}, Outcome.SUCCESS),
        # the task's own goal held at some step but not at the end: no other goal, so nothing reached
        (TASK, "extended", False, {TASK: 12}, Outcome.NO_GOAL_REACHED),
        (TASK, "extended", False, {TASK: 12, "spatial/s0/bowl-on-stove": 30}, Outcome.DID_OTHER_TASK),
    ],
)
def test_classify(task, kind, success, reached, outcome):
    assert classify(task, kind, SOURCE, success, reached) is outcome


ORDERED = "goal/s0/first-open-cabinet-top-drawer-then-black-bowl-on-plate"


@pytest.mark.parametrize(
    ("success", "reached", "wrong_order", "outcome"),
    [
        (True, {ORDERED: 90, SOURCE: 40}, False, Outcome.SUCCESS),
        # both sub-goals done, the source's first: right goals, wrong order (named before the source task)
        (False, {SOURCE: 40}, True, Outcome.WRONG_ORDER),
        # only the source's sub-goal done: the source task
        (False, {SOURCE: 40}, False, Outcome.DID_SOURCE_TASK),
        (False, {}, False, Outcome.NO_GOAL_REACHED),
    ],
)
def test_classify_an_ordered_task(success, reached, wrong_order, outcome):
    assert classify(ORDERED, "extended", SOURCE, success, reached, wrong_order=wrong_order) is outcome


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
    assert achieved(_record(success=True)) == TASK
    assert achieved(_record(reached={SOURCE: 9, "b": 4, "a": 4})) == "a"
    assert achieved(_record(reached={"a": 4, "b": 4})) == achieved(_record(reached={"b": 4, "a": 4})) == "a"
    assert achieved(_record(reached={"a": 20, "z": 3})) == "z"  # the earliest step first, the name only on ties
    assert achieved(_record(reached={SOURCE: 9})) == SOURCE
    assert achieved(_record()) == "none"
    # one goal of a shared layout (LIBERO-goal's) is every scene's task: the episode's own scene names it
    shared = {"goal/s0/bowl-on-stove": 7, "goal/s8/bowl-on-stove": 7, "goal/s9/bowl-on-stove": 7}
    assert achieved(_record(task_id="goal/s8/bowl-on-plate", reached=shared)) == "goal/s8/bowl-on-stove"
    earlier = {**shared, "goal/s1/plate-on-stove": 6}
    assert achieved(_record(task_id="goal/s8/bowl-on-plate", reached=earlier)) == "goal/s1/plate-on-stove"


def test_the_outcome_names_are_the_stored_strings():
    assert [o.value for o in Outcome] == [
        "success", "persisted", "wrong_order", "did_source_task", "did_other_task", "no_goal_reached",
        "policy_error", "gap"
    ]  # fmt: skip
    assert Outcome.GAP not in JUDGED_OUTCOMES and len(JUDGED_OUTCOMES) == len(Outcome) - 1
    assert [s.value for s in Status] == ["done", "gap"]


def test_gaps_are_not_judged_and_the_key_names_the_episode():
    assert _record().judged and not _record(status="gap").judged
    assert _record(status=Status.DONE).judged and not _record(status=Status.GAP).judged
    assert _record(success=True, outcome="success").judged  # judged is about the status, not the result
    assert _record(condition="empty").key == EpisodeKey(TASK, 0, 0, "empty")
    assert _record(init_index=3, seed=1003).key == EpisodeKey(TASK, 3, 1003, "given")
    assert EpisodeKey(TASK, 3, 1003).label() == f"{TASK}#3/seed1003/given"


def test_the_stored_columns_are_the_record_fields():
    assert [c.name for c in COLUMNS] == [f.name for f in fields(EpisodeRecord)]
    assert KEY_COLUMNS == ("task_id", "init_index", "seed", "condition")
    assert tuple(f.name for f in fields(EpisodeKey)) == KEY_COLUMNS
    assert [c.name for c in COLUMNS[: len(KEY_COLUMNS)]] == list(KEY_COLUMNS)  # the record starts with its key


def test_each_column_has_the_type_and_nullability_of_its_field():
    by_name = {c.name: c for c in COLUMNS}
    expected = {
        "task_id": (str, False),
        "init_index": (int, False),
        "success": (bool, False),
        "failure_kind": (str, True),
        "error": (str, True),
        "reached": (dict, False),
        "goals_at_end": (list, False),
        "physics": (dict, False),
        "wall_time_s": (float, False),
        "video": (str, True),
    }
    assert {n: (by_name[n].kind, by_name[n].nullable) for n in expected} == expected
    assert [c.name for c in COLUMNS if c.json] == [
        "reached", "goals_at_start", "goals_at_end", "cameras", "physics", "instructions"
    ]  # fmt: skip
    assert [c.name for c in COLUMNS if c.nullable] == ["failure_kind", "error", "video"]
    assert by_name["success"].ddl() == "success INTEGER NOT NULL"
    assert by_name["error"].ddl() == "error TEXT"
    assert by_name["wall_time_s"].ddl() == "wall_time_s REAL NOT NULL"
    assert by_name["status"].ddl() == "status TEXT NOT NULL CHECK (status IN ('done', 'gap'))"


def test_a_record_as_plain_data():
    data = record_dict(_record(status=Status.GAP, outcome=Outcome.GAP, reached={SOURCE: 2}))
    assert type(data["status"]) is str and data["status"] == "gap"
    assert type(data["outcome"]) is str and data["outcome"] == "gap"
    assert data["reached"] == {SOURCE: 2} and list(data) == [c.name for c in COLUMNS]


@pytest.mark.parametrize(
    ("success", "reached", "outcome"),
    [
        (True, {TASK: 90, SOURCE: 30}, Outcome.SUCCESS),
        (False, {SOURCE: 30}, Outcome.PERSISTED),  # the first instruction's goal, reached after the switch
        (False, {SOURCE: 20}, Outcome.PERSISTED),  # at the switch's step: after the policy was told
        (False, {SOURCE: 12}, Outcome.DID_SOURCE_TASK),  # done before the switch: what it was asked then
        (False, {}, Outcome.NO_GOAL_REACHED),
    ],
)
def test_classify_a_switch(success, reached, outcome):
    """switch:20 on an extended task: it starts under its source's instruction, its own from step 20."""
    assert classify(TASK, "extended", SOURCE, success, reached, switched=(SOURCE, 20)) == outcome
    if outcome is Outcome.PERSISTED:  # without the switch the same episode did its source task
        assert classify(TASK, "extended", SOURCE, success, reached) == Outcome.DID_SOURCE_TASK


def test_a_switch_at_the_first_step_persisted_only_if_the_first_goal_was_reached():
    assert classify(TASK, "extended", SOURCE, False, {}, switched=(SOURCE, 1)) == Outcome.NO_GOAL_REACHED
    assert classify(TASK, "extended", SOURCE, False, {SOURCE: 1}, switched=(SOURCE, 1)) == Outcome.PERSISTED
