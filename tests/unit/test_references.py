"""Referring expressions resolved on hand-built scenes: each relation, each viewpoint, and the moka pots; a
finding's words."""

from __future__ import annotations

import numpy as np
import pytest

from langgap.audit.reference_check import judged_findings
from langgap.audit.references import Layout, View, expected_entity, mentions, outcome, resolve
from langgap.bddl import BddlProblem, Region
from langgap.goals import goal_from_strings

# The robot looks along +x (its left is +y); the agentview camera looks back at it along -x (its right is +y);
# the policy's image is the camera's mirrored left to right (its right is -y again).
ROBOT = View("robot", right=np.array([0.0, -1.0, 0.0]), forward=np.array([1.0, 0.0, 0.0]))
CAMERA = View("camera", right=np.array([0.0, 1.0, 0.0]), forward=np.array([-1.0, 0.0, 0.0]))
POLICY = View("policy image", right=np.array([0.0, -1.0, 0.0]), forward=np.array([-1.0, 0.0, 0.0]))

SPATIAL = BddlProblem(
    problem_name="libero_tabletop_manipulation",
    language="",
    objects={
        "akita_black_bowl_1": "akita_black_bowl",
        "akita_black_bowl_2": "akita_black_bowl",
        "plate_1": "plate",
        "glazed_rim_porcelain_ramekin_1": "glazed_rim_porcelain_ramekin",
        "cookies_1": "cookies",
    },
    fixtures={"main_table": "table", "wooden_cabinet_1": "wooden_cabinet", "flat_stove_1": "flat_stove"},
    regions=(
        Region("top_region", "wooden_cabinet_1"),
        Region("top_side", "wooden_cabinet_1"),
        Region("cook_region", "flat_stove_1"),
    ),
    obj_of_interest=(),
    init=(),
    goal=(),
)
MOKA = BddlProblem(
    problem_name="libero_kitchen_tabletop_manipulation",
    language="",
    objects={"moka_pot_1": "moka_pot", "moka_pot_2": "moka_pot"},
    fixtures={"flat_stove_1": "flat_stove"},
    regions=(Region("cook_region", "flat_stove_1"),),
    obj_of_interest=(),
    init=(),
    goal=(),
)


def _layout(supports=(), **positions) -> Layout:
    where = {name: np.array([*xy, 0.9]) for name, xy in positions.items()}
    return Layout(where, frozenset(supports), np.array([0.0, 0.0, 0.9]))


def _picks(sentence: str, scene: BddlProblem, layout: Layout, view: View = ROBOT) -> tuple[str, ...]:
    first = next(m for m in mentions(sentence, scene) if m.role != "landmark")
    return resolve(first, scene, layout, view)


BOWLS = _layout(
    akita_black_bowl_1=(0.0, 0.1),
    akita_black_bowl_2=(0.0, 0.4),
    plate_1=(0.0, 0.0),
    glazed_rim_porcelain_ramekin_1=(0.0, 0.2),
    cookies_1=(0.3, 0.4),
)


def test_between_picks_the_one_on_the_segment_and_not_between_the_other():
    sentence = "pick up the black bowl {} the plate and the ramekin and place it on the plate"
    assert _picks(sentence.format("between"), SPATIAL, BOWLS) == ("akita_black_bowl_1",)
    assert _picks(sentence.format("not between"), SPATIAL, BOWLS) == ("akita_black_bowl_2",)
    beyond = _layout(akita_black_bowl_1=(0.0, -0.1), akita_black_bowl_2=(0.0, 0.4), plate_1=(0.0, 0.0),
                     glazed_rim_porcelain_ramekin_1=(0.0, 0.2), cookies_1=(0.3, 0.4))  # fmt: skip
    assert _picks(sentence.format("between"), SPATIAL, beyond) == ()


def _bowls(one: tuple[float, float], two: tuple[float, float]) -> Layout:
    """The plate at the origin, the ramekin 20 cm along +y (the segment), the two bowls where given."""
    return _layout(akita_black_bowl_1=one, akita_black_bowl_2=two, plate_1=(0.0, 0.0),
                   glazed_rim_porcelain_ramekin_1=(0.0, 0.2), cookies_1=(0.3, 0.4))  # fmt: skip


def test_between_is_bounded_along_and_across_the_segment_and_picks_neither_when_none_fits():
    between = "pick up the black bowl between the plate and the ramekin and place it on the plate"
    not_between = between.replace("between", "not between")
    # One bowl past the ramekin (t 1.26), the other level with the segment's middle but 30 cm off it.
    past_the_end = _bowls((0.0, 0.252), (0.3, 0.1))
    assert _picks(between, SPATIAL, past_the_end) == ()
    assert _picks(not_between, SPATIAL, past_the_end) == ("akita_black_bowl_1", "akita_black_bowl_2")
    # 6 cm off a 20 cm segment (BETWEEN_WIDTH: a quarter of it, 5 cm) is beside it.
    assert _picks(between, SPATIAL, _bowls((0.06, 0.1), (0.3, 0.1))) == ()
    assert _picks(between, SPATIAL, _bowls((0.0, 0.211), (0.3, 0.1))) == ()  # t 1.055: past BETWEEN_ENDS
    # Within both bounds (t 1.045 on the line; 4.9 cm off at the middle) both fit; the nearer the line is picked.
    assert _picks(between, SPATIAL, _bowls((0.0, 0.209), (0.3, 0.1))) == ("akita_black_bowl_1",)
    assert _picks(between, SPATIAL, _bowls((0.049, 0.1), (0.3, 0.1))) == ("akita_black_bowl_1",)
    assert _picks(between, SPATIAL, _bowls((0.049, 0.1), (0.0, 0.209))) == ("akita_black_bowl_2",)
    assert _picks(not_between, SPATIAL, _bowls((0.049, 0.1), (0.0, 0.209))) == ("akita_black_bowl_1",)


def test_next_to_picks_the_nearest_and_is_ambiguous_within_the_margin():
    sentence = "pick up the black bowl next to the cookie box and place it on the plate"
    assert _picks(sentence, SPATIAL, BOWLS) == ("akita_black_bowl_2",)
    tie = _layout(akita_black_bowl_1=(0.0, 0.1), akita_black_bowl_2=(0.0, 0.29), plate_1=(0.0, 0.0),
                  glazed_rim_porcelain_ramekin_1=(0.0, 0.2), cookies_1=(0.3, 0.4))  # fmt: skip
    assert _picks("pick up the bowl next to the ramekin", SPATIAL, tie) == ("akita_black_bowl_1", "akita_black_bowl_2")


def test_a_side_of_a_landmark_depends_on_the_viewpoint():
    sentence = "pick up the black bowl on the right of the plate and place it on the stove"
    assert _picks(sentence, SPATIAL, BOWLS, CAMERA) == ("akita_black_bowl_1",)  # nearer of the two at +y
    assert _picks(sentence, SPATIAL, BOWLS, ROBOT) == ()
    ahead = _layout(akita_black_bowl_1=(-0.2, 0.0), akita_black_bowl_2=(0.3, 0.0), plate_1=(0.0, 0.0),
                    glazed_rim_porcelain_ramekin_1=(0.5, 0.5), cookies_1=(0.5, -0.5))  # fmt: skip
    front = "pick up the black bowl in front of the plate and place it on the stove"
    assert _picks(front, SPATIAL, ahead, ROBOT) == ("akita_black_bowl_1",)  # nearer the robot
    assert _picks(front, SPATIAL, ahead, CAMERA) == ("akita_black_bowl_2",)  # nearer the camera
    assert _picks(front.replace("in front of", "behind"), SPATIAL, ahead, ROBOT) == ("akita_black_bowl_2",)


def test_on_in_and_from_ask_the_simulators_supports():
    on_box = _layout(supports={("akita_black_bowl_2", "cookies_1")}, **{k: v[:2] for k, v in BOWLS.positions.items()})
    assert _picks("pick up the black bowl on the cookie box and place it on the plate", SPATIAL, on_box) == (
        "akita_black_bowl_2",
    )
    drawer = _layout(supports={("akita_black_bowl_1", "wooden_cabinet_1_top_region")},
                     **{k: v[:2] for k, v in BOWLS.positions.items()})  # fmt: skip
    sentence = "pick up the black bowl in the top drawer of the wooden cabinet and place it on the plate"
    assert _picks(sentence, SPATIAL, drawer) == ("akita_black_bowl_1",)
    stove = _layout(supports={("akita_black_bowl_1", "flat_stove_1_cook_region")},
                    **{k: v[:2] for k, v in BOWLS.positions.items()})  # fmt: skip
    assert _picks("lift bowl from stove and set on plate", SPATIAL, stove) == ("akita_black_bowl_1",)
    assert _picks("pick up the black bowl on the stove", SPATIAL, BOWLS) == ()


def test_from_table_center_picks_the_nearest_to_the_tables_centre():
    assert _picks("pick up the black bowl from table center and place it on the plate", SPATIAL, BOWLS) == (
        "akita_black_bowl_1",
    )


def test_the_left_moka_pot_is_the_goals_from_the_robot_and_the_other_from_the_camera():
    """LIBERO-PRO's libero10/s8/pro-task: its goal names moka_pot_1, which starts at larger y."""
    sentence = "put the left moka pot on the stove"
    goal = goal_from_strings(["(On moka_pot_1 flat_stove_1_cook_region)", "(Turnon flat_stove_1)"])
    layout = _layout(moka_pot_1=(0.0, 0.15), moka_pot_2=(0.0, -0.1), flat_stove_1=(0.0, 0.0))
    found = mentions(sentence, MOKA)
    pot = next(m for m in found if m.category == "moka_pot")
    assert (pot.side, pot.role, pot.phrase) == ("left", "object", "left moka pot")
    expected = expected_entity(pot, found, goal, MOKA)
    assert expected == "moka_pot_1"
    assert outcome(resolve(pot, MOKA, layout, ROBOT), expected) == "goal's"
    assert outcome(resolve(pot, MOKA, layout, CAMERA), expected) == "other"
    assert outcome(resolve(pot, MOKA, layout, POLICY), expected) == "goal's"
    both = next(m for m in mentions("put both moka pots on the stove", MOKA) if m.category == "moka_pot")
    assert both.plural and expected_entity(both, [both], goal, MOKA) is None


@pytest.mark.parametrize(
    ("sentence", "roles"),
    [
        ("put the white mug on the left plate and put the yellow and white mug on the right plate",
         [("white mug", "object"), ("plate", "target"), ("yellow and white mug", "object"), ("plate", "target")]),
        ("place it on the plate after you pick up the ramekin", [("plate", "target"), ("ramekin", "object")]),
        ("the ramekin should be picked up and placed on the plate", [("ramekin", "object"), ("plate", "target")]),
        ("pick up anything but the ramekin and place it on the plate", [("ramekin", "excluded"), ("plate", "target")]),
        # LIBERO-Plus's rewordings of libero_10 scene 4 ("-3", "-28", "-35"): where the mugs go
        ("Lets have the white mug on the left plate and the yellow and white mug on the right plate",
         [("white mug", "object"), ("plate", "target"), ("yellow and white mug", "object"), ("plate", "target")]),
        ("Arrange the white mug on the left plate and set the yellow and white mug on the right plate",
         [("white mug", "object"), ("plate", "target"), ("yellow and white mug", "object"), ("plate", "target")]),
        ("the white mug belongs on the left plate and the yellow and white mug on the right plate",
         [("white mug", "object"), ("plate", "target"), ("yellow and white mug", "object"), ("plate", "target")]),
    ],
)  # fmt: skip
def test_each_mention_gets_its_role_in_the_sentence(sentence, roles):
    mugs = {"porcelain_mug_1": "porcelain_mug", "white_yellow_mug_1": "white_yellow_mug", "plate_2": "plate"}
    scene = BddlProblem("p", "", {**SPATIAL.objects, **mugs}, {}, (), (), (), ())
    assert [(m.text, m.role) for m in mentions(sentence, scene)] == roles


def test_the_target_expected_is_the_one_its_clauses_object_goes_to():
    scene = BddlProblem("p", "", {"porcelain_mug_1": "porcelain_mug", "white_yellow_mug_1": "white_yellow_mug",
                                  "plate_1": "plate", "plate_2": "plate"}, {}, (), (), (), ())  # fmt: skip
    goal = goal_from_strings(["(On porcelain_mug_1 plate_1)", "(On white_yellow_mug_1 plate_2)"])
    found = mentions("put the white mug on the left plate and put the yellow and white mug on the right plate", scene)
    plates = [m for m in found if m.category == "plate"]
    assert [(m.side, expected_entity(m, found, goal, scene)) for m in plates] == [
        ("left", "plate_1"),
        ("right", "plate_2"),
    ]


def test_words_the_reader_does_not_follow_leave_the_expression_unread():
    found = mentions(
        "could you put the black bowl on the plate its the one sitting between the plate and ramekin", SPATIAL
    )
    assert next(m for m in found if m.category == "akita_black_bowl").unread
    assert not next(m for m in mentions("pick up the bowl and place it on the plate", SPATIAL)).unread


def test_a_finding_says_what_the_expression_picks_from_every_viewpoint():
    sentence = "put the left moka pot on the stove"
    pot = next(m for m in mentions(sentence, MOKA) if m.category == "moka_pot")
    by_view = {
        "robot": [(0, ("moka_pot_1",)), (1, ("moka_pot_1",))],
        "camera": [(0, ("moka_pot_2",)), (1, ())],
        "policy image": [(0, ("moka_pot_1",)), (1, ("moka_pot_1",))],
    }
    views = (
        "robot: the goal's on init state(s) 0–1 (2 of 2); camera (raw render): moka_pot_2 on init state(s) 0 (1 of 2), "
        "neither on init state(s) 1 (1 of 2); policy's image: the goal's on init state(s) 0–1 (2 of 2)"
    )
    found = judged_findings("libero10/s8/pro-task", sentence, pot, "moka_pot_1", by_view, 2)
    assert [(f.name, f.task, f.detail) for f in found] == [
        ("sentence picks another object", "libero10/s8/pro-task",
         f"'left moka pot' picks moka_pot_2, not the goal's moka_pot_1 — {views} — in {sentence!r}"),
        ("sentence picks no object", "libero10/s8/pro-task",
         f"'left moka pot' picks neither — {views} — in {sentence!r}"),
    ]  # fmt: skip
    right = {view: [(0, ("moka_pot_1",))] for view in by_view}
    assert judged_findings("libero10/s8/pro-task", sentence, pot, "moka_pot_1", right, 2) == []
