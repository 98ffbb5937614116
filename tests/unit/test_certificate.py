"""When a drawer's reachability analysis certifies it infeasible."""

from __future__ import annotations

import math

from langgap.bddl import Predicate
from langgap.catalog.catalog import load_catalog
from langgap.certify import TOLERANCE_M, HandleReach, PoseResult, required_opening, sharing
from langgap.goals import parse_goal


def _pose(hand: float, arm: float = 0.0, reachable: bool = True) -> PoseResult:
    if not reachable:
        return PoseResult(0, 0.0, 0.0, 0, False, math.nan, math.nan, "")
    return PoseResult(30, 0.01, 0.0, 0, True, hand, arm, "table_collision" if hand else "")


def _reach(*poses: PoseResult, gap: float = 0.016) -> HandleReach:
    return HandleReach("goal/s0/open-cabinet-bottom-drawer", 0, (0.04, -0.13, 0.95), list(poses), "a family", gap)


def test_one_clear_pose_refutes_the_certificate():
    found = _reach(_pose(0.02), _pose(0.0), _pose(0.0, reachable=False))
    assert not found.certified and found.certificate() == "" and len(found.clear) == 1


def test_a_hand_in_a_fixture_everywhere_certifies():
    found = _reach(_pose(0.03), _pose(0.021), _pose(0.0, reachable=False))
    assert found.certified
    text = found.certificate()
    assert "reaches 2 (none found for the other 1" in text and "21 mm into table_collision" in text
    assert "gap between the bar and the drawer's face is 16 mm" in text


def test_a_bar_a_finger_can_hook_is_not_certified():
    assert not _reach(_pose(0.03), gap=0.025).certified


def test_an_arm_collision_alone_does_not_certify():
    # The hand is clear and only the arm meets a fixture: another arm configuration may not.
    found = _reach(_pose(0.0, arm=0.05), _pose(0.03))
    assert not found.clear and not found.certified
    assert not _reach(_pose(TOLERANCE_M), _pose(0.03)).certified  # within the tolerance is clear


def test_the_drawer_a_goal_needs_in_every_way_of_meeting_it():
    bottom = Predicate("Open", ("wooden_cabinet_1_bottom_region",))
    assert required_opening(parse_goal("(And (Open wooden_cabinet_1_bottom_region))")) == bottom
    ordered = "(Then (Open wooden_cabinet_1_bottom_region) (On akita_black_bowl_1 plate_1))"
    assert required_opening(parse_goal(ordered)) == bottom
    # a goal that can be met without the drawer, or that needs two, is not this drawer's to certify
    either = "(Or (Open wooden_cabinet_1_bottom_region) (On akita_black_bowl_1 plate_1))"
    assert required_opening(parse_goal(either)) is None
    both = "(And (Open wooden_cabinet_1_bottom_region) (Open wooden_cabinet_1_top_region))"
    assert required_opening(parse_goal(both)) is None
    assert required_opening(parse_goal("(And (On akita_black_bowl_1 plate_1))")) is None


def test_a_certificate_holds_for_every_task_needing_the_drawer_on_the_same_scene():
    beyond = load_catalog("langgap-beyond")
    task = beyond.get("spatial/s0/first-black-bowl-1-on-plate-then-open-cabinet-bottom-drawer")
    assert [t.id for t in sharing(beyond, task)] == [
        "spatial/s0/first-black-bowl-1-on-plate-then-open-cabinet-bottom-drawer",
        "spatial/s0/first-open-cabinet-bottom-drawer-then-black-bowl-1-on-plate",
    ]  # not the middle drawer's tasks, nor spatial/s1's bottom drawer (another scene)
    assert sharing(beyond, beyond.get("spatial/s0/black-bowl-1-on-plate")) == []
