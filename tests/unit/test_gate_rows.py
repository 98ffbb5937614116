"""The gate's row per task (`langgap.gate.rows.task_row`): which checks a task passes from the oracle's
episodes, the reason it names when one fails, the figures it shows, and the verdict it records."""

from __future__ import annotations

import dataclasses

import pytest

from langgap.catalog.catalog import load_catalog
from langgap.catalog.verdicts import SETTLE_CHECK
from langgap.gate.rows import SETTLE_TOLERANCE_M, goals_exclude, task_row
from langgap.goals import parse_goal
from langgap.vocabulary import Verdict
from tests.support.reports import episode

SOURCE = "spatial/s0/black-bowl-1-on-plate"
ELSEWHERE = "spatial/s0/black-bowl-1-on-stove"  # the source's bowl on another target: the goals exclude
OTHER_OBJECT = "spatial/s0/ramekin-on-plate"  # another object: both goals can hold together
RATE_CHECK = "success >= 90%"


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap99")


def _episodes(task_id: str, wins: int, losses: int = 0, gaps: int = 0, **kw) -> list:
    """The oracle's episodes of `task_id`: `wins` successes, then `losses` failures, then `gaps`, init 0 on."""
    plan = [True] * wins + [False] * losses
    records = [
        dataclasses.replace(episode(OTHER_OBJECT, k, success=ok, **kw), task_id=task_id, steps=100 + k)
        for k, ok in enumerate(plan)
    ]
    start = len(plan)
    return records + [
        dataclasses.replace(episode(OTHER_OBJECT, start + k, gap=True), task_id=task_id) for k in range(gaps)
    ]


def test_goals_exclude_only_one_object_placed_on_two_targets():
    assert goals_exclude(parse_goal("(On bowl plate)"), parse_goal("(On bowl stove)"))
    assert goals_exclude(parse_goal("(In bowl drawer)"), parse_goal("(On bowl plate)"))
    assert not goals_exclude(parse_goal("(On bowl plate)"), parse_goal("(On bowl plate)"))  # the same target
    assert not goals_exclude(parse_goal("(On bowl plate)"), parse_goal("(On ramekin stove)"))  # other objects
    assert not goals_exclude(parse_goal("(Open drawer)"), parse_goal("(On bowl plate)"))  # not a placement
    assert not goals_exclude(parse_goal("(On bowl plate)"), parse_goal("(Open drawer)"))
    assert not goals_exclude(parse_goal("(On bowl plate)"), parse_goal("(And (On bowl stove) (On cup plate))"))
    assert not goals_exclude(parse_goal("(And (On bowl stove) (On cup plate))"), parse_goal("(On bowl plate)"))
    assert not goals_exclude(parse_goal("(Not (On bowl stove))"), parse_goal("(On bowl plate)"))


def test_a_task_the_oracle_does_passes_every_check(catalog):
    row = task_row(catalog.get(ELSEWHERE), catalog, _episodes(ELSEWHERE, 10), drift=0.001, demonstrated=[])
    assert row.feasible and row.reason == "" and row.word == Verdict.DOABLE
    assert row.checks == {
        RATE_CHECK: True,
        "goal false at t0": True,
        "source goal false at end": True,
        "env builds": True,
        SETTLE_CHECK: True,
    }
    assert (row.id, row.suite, row.dimension) == (ELSEWHERE, "libero_spatial", "change_target")
    assert (row.episodes, row.successes, row.rate, row.gaps) == (10, 10, 1.0, 0)
    assert (row.mean_steps, row.max_steps) == (104.5, 109)
    assert row.settle_drift_mm == pytest.approx(1.0)
    assert row.failed_inits == [] and not row.short


def test_below_the_rate_the_reason_names_the_oracles_count(catalog):
    records = _episodes(ELSEWHERE, 8, losses=2)
    row = task_row(catalog.get(ELSEWHERE), catalog, records, drift=0.0, demonstrated=[])
    assert not row.feasible and row.short and row.word == Verdict.UNPROVEN
    assert row.reason == "oracle 8/10" and row.checks[RATE_CHECK] is False
    assert row.failed_inits == [8, 9] and row.rate == 0.8
    assert (row.mean_steps, row.max_steps) == (103.5, 107)  # the successful episodes' steps only


def test_searched_demonstrations_count_toward_the_rate(catalog):
    records = _episodes(ELSEWHERE, 7, losses=3)
    row = task_row(catalog.get(ELSEWHERE), catalog, records, drift=0.0, demonstrated=[9])
    assert not row.feasible and row.reason == "oracle 7/10" and row.demonstrated_inits == [9] and row.short
    row = task_row(catalog.get(ELSEWHERE), catalog, records, drift=0.0, demonstrated=[9, 8])
    assert row.feasible and row.demonstrated_inits == [8, 9] and not row.short
    assert row.failed_inits == [7, 8, 9]  # still the oracle's failures


def test_no_successful_episode_has_no_steps(catalog):
    row = task_row(catalog.get(ELSEWHERE), catalog, _episodes(ELSEWHERE, 0, losses=3), drift=0.0, demonstrated=[])
    assert (row.mean_steps, row.max_steps, row.rate) == (0.0, 0, 0.0)
    assert row.reason == "oracle 0/3"


def test_a_goal_true_at_t0_is_a_failed_check(catalog):
    records = _episodes(ELSEWHERE, 9, goals_at_start=[ELSEWHERE])
    records += _episodes(ELSEWHERE, 1)
    row = task_row(catalog.get(ELSEWHERE), catalog, records, drift=0.0, demonstrated=[])
    assert row.goal_true_at_t0 == 9 and not row.feasible
    assert row.reason == "goal false at t0" and row.word == Verdict.UNPROVEN
    elsewhere = _episodes(ELSEWHERE, 10, goals_at_start=[SOURCE])  # another task's goal at t0 is no failure
    assert task_row(catalog.get(ELSEWHERE), catalog, elsewhere, drift=0.0, demonstrated=[]).feasible


def test_the_source_goal_at_the_end_fails_a_task_whose_goal_excludes_it(catalog):
    records = _episodes(ELSEWHERE, 10, goals_at_end=[SOURCE])
    row = task_row(catalog.get(ELSEWHERE), catalog, records, drift=0.0, demonstrated=[])
    assert row.source_true_at_end == 10 and row.reason == "source goal false at end" and not row.feasible
    # only the successful episodes count: a failure that ends in the source's goal is the policy's business
    records = _episodes(ELSEWHERE, 9, losses=1, goals_at_end=[SOURCE])
    assert task_row(catalog.get(ELSEWHERE), catalog, records, drift=0.0, demonstrated=[]).source_true_at_end == 9
    # a goal that can hold beside the source's (another object) is not checked
    records = _episodes(OTHER_OBJECT, 10, goals_at_end=[SOURCE])
    row = task_row(catalog.get(OTHER_OBJECT), catalog, records, drift=0.0, demonstrated=[])
    assert row.source_true_at_end == 0 and row.feasible


def test_an_original_is_never_checked_against_its_own_goal(catalog):
    records = _episodes(SOURCE, 10, goals_at_end=[SOURCE])
    row = task_row(catalog.get(SOURCE), catalog, records, drift=0.0, demonstrated=[])
    assert row.source_true_at_end == 0 and row.feasible


def test_a_gap_fails_env_builds_and_is_not_judged(catalog):
    records = _episodes(ELSEWHERE, 10, gaps=1)
    row = task_row(catalog.get(ELSEWHERE), catalog, records, drift=0.0, demonstrated=[])
    assert (row.episodes, row.gaps) == (10, 1) and row.reason == "env builds" and not row.feasible
    row = task_row(catalog.get(ELSEWHERE), catalog, _episodes(ELSEWHERE, 0, gaps=2), drift=0.0, demonstrated=[])
    assert row.checks["env builds"] is False and row.episodes == 0 and not row.short and row.rate == 0.0
    row = task_row(catalog.get(ELSEWHERE), catalog, [], drift=0.0, demonstrated=[])  # no episode at all
    assert row.checks["env builds"] is False and not row.feasible
    one = task_row(catalog.get(ELSEWHERE), catalog, _episodes(ELSEWHERE, 1), drift=0.0, demonstrated=[])
    assert one.checks["env builds"] and one.feasible  # a single init state is a gate too


def test_the_scene_settles_up_to_its_tolerance(catalog):
    task, records = catalog.get(ELSEWHERE), _episodes(ELSEWHERE, 10)
    assert task_row(task, catalog, records, drift=SETTLE_TOLERANCE_M, demonstrated=[]).feasible
    row = task_row(task, catalog, records, drift=SETTLE_TOLERANCE_M + 1e-6, demonstrated=[])
    assert row.reason == SETTLE_CHECK and row.word == Verdict.UNSETTLED


def test_every_failed_check_is_named_in_order(catalog):
    records = _episodes(ELSEWHERE, 1, losses=1, gaps=1, goals_at_start=[ELSEWHERE], goals_at_end=[SOURCE])
    row = task_row(catalog.get(ELSEWHERE), catalog, records, drift=1.0, demonstrated=[])
    assert row.reason == "oracle 1/2; goal false at t0; source goal false at end; env builds; " + SETTLE_CHECK


def test_the_recorded_verdict_carries_the_rows_evidence(catalog):
    records = _episodes(ELSEWHERE, 7, losses=3)
    row = task_row(catalog.get(ELSEWHERE), catalog, records, drift=0.0, demonstrated=[8, 9])
    row.demonstration = "demonstrations/x"
    verdict = row.verdict(10, made_by="oracle@abc", physics={"mujoco": "3.2.3"})
    assert (verdict.episodes, verdict.successes, verdict.feasible, verdict.reason) == (10, 7, True, "")
    assert (verdict.inits, verdict.failed_inits, verdict.made_by) == (10, (7, 8, 9), "oracle@abc")
    assert verdict.physics == {"mujoco": "3.2.3"} and verdict.proof == ""
    assert (verdict.demonstration, verdict.demonstrated_inits) == ("demonstrations/x", (8, 9))
    failed = task_row(catalog.get(ELSEWHERE), catalog, records, drift=0.0, demonstrated=[])
    failed.demonstration = "demonstrations/x"  # no searched episode: the path is not recorded
    verdict = failed.verdict(10, proof="the plate is out of reach")
    assert verdict.demonstration == "" and verdict.demonstrated_inits == () and verdict.physics == {}
    assert verdict.made_by == ""
    assert verdict.proof == "the plate is out of reach" and verdict.reason == "oracle 7/10"
