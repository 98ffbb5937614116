"""Proofs of impossibility on hand-made facts: each prover proves beyond its bound, and never short of it."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from langgap.bddl import Predicate
from langgap.catalog.catalog import load_catalog
from langgap.gate import proofs
from langgap.gate.proofs import (
    MAX_STEP_M,
    PANDA_REACH_M,
    Body,
    Facts,
    Proof,
    Site,
    out_of_reach,
    prove,
    too_few_steps,
)
from langgap.goals import parse_goal

SHOULDER = (0.0, 0.0, 1.0)
HAND = 0.13
REACH = PANDA_REACH_M + HAND  # 0.985 m: the gripper's farthest point from the shoulder
REGION_SIZE = (0.05, 0.05, 0.01)
# a ball around the site holds every origin On the region: its half-sizes, up to 10 cm above its top
ON_RADIUS = math.sqrt(0.05**2 + 0.05**2 + (0.01 + proofs.ON_REGION_ABOVE_M) ** 2)
ON_FAR = "(On bowl_1 table_far_region)"


def _box(origin, half, *, movable=True, travel=0.0) -> Body:
    origin = np.asarray(origin, dtype=np.float64)
    return Body(origin, origin - half, origin + half, movable, travel)


def _facts(*, bowl=(0.5, 0.0, 0.9), region=(0.5, 0.0, 1.0), holding=(), sites=(), **bodies) -> Facts:
    """The shoulder 1 m above the origin, a bowl (+-4 cm) on the table, a region ahead, and `bodies`."""
    return Facts(
        shoulder=np.array(SHOULDER),
        hand=HAND,
        eef=np.array([0.4, 0.0, 1.2]),
        grip_span=0.17,
        bodies={"bowl_1": _box(bowl, 0.04), **bodies},
        sites={"table_far_region": Site(region, REGION_SIZE, "table"), **dict(sites)},
        holding=frozenset(holding),
    )


def _at(x: float) -> tuple[float, float, float]:
    return (x, 0.0, 1.0)  # level with the shoulder, `x` ahead of it


@pytest.fixture(scope="module")
def base_task():
    return load_catalog("langgap99").get("spatial/s0/black-bowl-1-on-plate")


def _task(base, goal: str, max_steps: int = 300):
    return dataclasses.replace(base, goal=parse_goal(goal), max_steps=max_steps)


def test_a_region_beyond_reach_is_proven_out_of_reach(base_task):
    facts = _facts(region=_at(2.0))
    proof = out_of_reach(_task(base_task, ON_FAR), facts)
    assert proof is not None
    text = proof.text()
    assert "(On bowl_1 table_far_region) can never hold" in text
    for assumption in proof.assumptions:
        assert assumption in text  # printed with every assumption it rests on
    assert "base does not move" in text and "pushing chain" in text and "stated with this assumption" in text
    assert "0.855" in text and "Franka's datasheet" in text
    assert f"hand, flange to its farthest point, m {HAND:.3f}" in text  # every figure of the argument
    assert prove(_task(base_task, ON_FAR), facts) == proof


def test_no_proof_up_to_the_bound_and_one_just_beyond_it(base_task):
    task = _task(base_task, ON_FAR)
    # the bowl's origin goes at most the gripper's reach plus the bowl's extent (its box's far corner)
    carried = REACH + math.sqrt(3) * 0.04
    bound = carried + ON_RADIUS  # the region's centre this far from the shoulder: its nearest point at `carried`
    assert out_of_reach(task, _facts(region=_at(bound - 1e-6))) is None
    assert out_of_reach(task, _facts(region=_at(bound + 1e-6))) is not None
    assert out_of_reach(task, _facts(region=_at(0.6))) is None  # an ordinary reachable region


def test_a_held_object_extends_the_reach(base_task):
    task = _task(base_task, ON_FAR)
    assert out_of_reach(task, _facts(region=_at(1.35))) is not None
    # a plate 57 cm across (its box's diagonal) may push the bowl that much farther than the gripper reaches
    plate = _box([0.3, 0.3, 0.9], [0.2, 0.2, 0.01])
    assert out_of_reach(task, _facts(region=_at(1.35), plate_1=plate)) is None


def test_a_drawer_the_gripper_pulls_may_carry_what_it_touches(base_task):
    task = _task(base_task, ON_FAR)
    # a cabinet within reach whose drawers travel 0.5 m: what lies in a drawer goes where the drawer goes
    cabinet = _box([0.7, 0.0, 0.8], [0.2, 0.2, 0.2], movable=False, travel=0.5)
    assert out_of_reach(task, _facts(region=_at(1.45))) is not None
    assert out_of_reach(task, _facts(region=_at(1.45), cabinet_1=cabinet)) is None
    # a drawer's inside moves with the drawer, unless nothing can touch the cabinet
    in_drawer = _task(base_task, "(In bowl_1 cabinet_1_bottom_region)")
    inside = {"cabinet_1_bottom_region": Site([1.6, 0.0, 0.8], REGION_SIZE, "cabinet_1", jointed=True)}
    far = _box([1.8, 0.0, 0.8], [0.25, 0.25, 0.25], movable=False, travel=0.5)
    assert out_of_reach(in_drawer, _facts(cabinet_1=far, sites=inside)) is not None
    near = _box([1.0, 0.0, 0.8], [0.25, 0.25, 0.25], movable=False, travel=0.5)
    assert out_of_reach(in_drawer, _facts(cabinet_1=near, sites=inside)) is None


def test_an_articulated_part_nothing_can_touch(base_task):
    task = _task(base_task, "(Open cabinet_1_bottom_region)")
    inside = {"cabinet_1_bottom_region": Site([2.0, 0.0, 0.8], REGION_SIZE, "cabinet_1", jointed=True)}
    far = _box([2.1, 0.0, 0.8], [0.2, 0.2, 0.2], movable=False, travel=0.3)
    proof = out_of_reach(task, _facts(cabinet_1=far, sites=inside))
    assert proof is not None and "(Open cabinet_1_bottom_region) can never hold" in proof.claim
    assert any("cabinet_1's nearest point from the shoulder" in name for name in proof.figures)
    # within reach, or open already: no proof
    near = _box([0.9, 0.0, 0.8], [0.2, 0.2, 0.2], movable=False, travel=0.3)
    assert out_of_reach(task, _facts(cabinet_1=near, sites=inside)) is None
    opened = Predicate("Open", ("cabinet_1_bottom_region",))
    assert out_of_reach(task, _facts(cabinet_1=far, sites=inside, holding=(opened,))) is None


def test_an_object_nothing_can_touch_stays_where_it_is(base_task):
    task = _task(base_task, ON_FAR)
    assert out_of_reach(task, _facts(bowl=(1.5, 0.0, 0.9))) is not None  # the bowl can never be fetched
    assert out_of_reach(task, _facts()) is None  # on the region already: it holds at t0


def test_a_loose_target_counts_only_where_nothing_can_move_it(base_task):
    task = _task(base_task, "(On bowl_1 plate_1)")
    far_plate = _box([2.0, 0.0, 0.9], [0.1, 0.1, 0.01])
    assert out_of_reach(task, _facts(plate_1=far_plate)) is not None  # nothing can touch it: it stays 2 m away
    # beyond the gripper, yet within what the bowl held can push: the plate may come (no proof)
    pushed = _box([REACH + 0.05, 0.0, 1.0], [0.1, 0.1, 0.01])
    assert out_of_reach(task, _facts(plate_1=pushed)) is None
    assert out_of_reach(task, _facts(plate_1=_box([0.6, 0.2, 0.9], [0.1, 0.1, 0.01]))) is None


def test_the_goal_decides_which_atoms_are_needed(base_task):
    far, near = ON_FAR, "(On bowl_1 table_near_region)"
    sites = {"table_near_region": Site([0.5, 0.3, 1.0], REGION_SIZE, "table")}

    def proven(goal: str) -> bool:
        return out_of_reach(_task(base_task, goal), _facts(region=_at(2.0), sites=sites)) is not None

    assert proven(f"(And {far} {near})") and proven(f"(Then {near} {far})")
    assert proven(f"(Or {far} (And {near} {far}))")
    assert not proven(f"(Or {far} {near})")  # the near one will do
    assert not proven(f"(Not {far})") and not proven(near)


# the bowl on the arm's left, its region on the right: both within reach, far apart
LEFT, RIGHT = (-0.3, 0.8, 0.9), (0.3, -0.8, 1.0)


def test_too_few_steps_beyond_the_step_limit_only(base_task):
    facts = _facts(bowl=LEFT, region=RIGHT)
    task = _task(base_task, ON_FAR, max_steps=300)
    assert out_of_reach(task, facts) is None and too_few_steps(task, facts) is None
    # by hand: the grip site comes within 0.17 + the bowl's extent of it, then carries it to the region
    near = 0.17 + math.sqrt(3) * 0.04
    to_bowl = math.dist((0.4, 0.0, 1.2), LEFT) - near
    with_it = math.dist(LEFT, RIGHT) - ON_RADIUS - 2 * near
    steps = (to_bowl + with_it) / MAX_STEP_M
    assert 20 < steps < 25
    limit = math.floor(steps)  # fewer steps than the travel needs at the largest step
    proof = too_few_steps(dataclasses.replace(task, max_steps=limit), facts)
    assert proof is not None
    text = proof.text()
    assert f"more than the task's {limit}" in text and f"{MAX_STEP_M:.4f}" in text
    assert "OSC target is clipped" in text and "pushing chain" in text
    for assumption in proof.assumptions:
        assert assumption in text
    assert too_few_steps(dataclasses.replace(task, max_steps=math.ceil(steps)), facts) is None
    assert prove(dataclasses.replace(task, max_steps=limit), facts) == proof


def test_too_few_steps_counts_nothing_done_already_and_the_cheapest_way(base_task):
    assert too_few_steps(_task(base_task, ON_FAR, max_steps=1), _facts()) is None  # holds at t0: no travel
    sites = {"table_near_region": Site([-0.3, 0.8, 1.0], REGION_SIZE, "table")}  # the bowl is on it already
    facts = _facts(bowl=LEFT, region=RIGHT, sites=sites)
    assert too_few_steps(_task(base_task, ON_FAR, max_steps=5), facts) is not None
    either = f"(Or {ON_FAR} (On bowl_1 table_near_region))"
    assert too_few_steps(_task(base_task, either, max_steps=5), facts) is None
    assert too_few_steps(_task(base_task, f"(Not {ON_FAR})", max_steps=1), facts) is None


def test_a_proof_lists_its_figures_and_assumptions():
    proof = Proof("No policy can.", ("the base is fixed", "nothing is thrown"), {"reach, m": 0.855, "at": "x"})
    assert proof.text() == (
        "No policy can. Figures: reach, m 0.855; at x. Assumptions: (1) the base is fixed (2) nothing is thrown"
    )
