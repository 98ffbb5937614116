"""The goal language, evaluated against a fake truth function (no simulator)."""

from __future__ import annotations

import pytest

from langgap.bddl import Predicate
from langgap.errors import BddlError
from langgap.goals import (
    And,
    Atom,
    GoalProgress,
    Not,
    Or,
    Then,
    atoms,
    choices,
    conjunction,
    goal_from_strings,
    goal_strings,
    holds_now,
    is_ordered,
    parse_goal,
    plain_atoms,
    plans,
    stages,
    unordered,
    witness,
)

BOWL_ON_PLATE = Predicate.parse("(On bowl_1 plate_1)")
BOWL_ON_RAMEKIN = Predicate.parse("(On bowl_1 ramekin_1)")
BOWL_IN_DRAWER = Predicate.parse("(In bowl_1 cabinet_1_top_region)")
OPEN_DRAWER = Predicate.parse("(Open cabinet_1_top_region)")


def run(goal, history: list[set[Predicate]]) -> list[bool]:
    """The goal's value at each step of a history of true-atom sets (step 0 first)."""
    progress = GoalProgress(goal)
    return [progress.observe(step, lambda p, true=true: p in true) for step, true in enumerate(history)]


@pytest.mark.parametrize(
    "text",
    [
        "(On bowl_1 plate_1)",
        "(And (On bowl_1 plate_1) (Open cabinet_1_top_region))",
        "(Or (On bowl_1 ramekin_1) (In bowl_1 cabinet_1_top_region))",
        "(Not (On bowl_1 plate_1))",
        "(Then (Open cabinet_1_top_region) (On bowl_1 plate_1))",
        "(And (Or (On bowl_1 ramekin_1) (On bowl_1 cookies_1)) (Not (On bowl_1 plate_1)))",
    ],
)
def test_parse_and_str_round_trip(text):
    assert str(parse_goal(text)) == text
    assert parse_goal(text.lower().replace("bowl_1", "bowl_1")) == parse_goal(text)  # names are case-insensitive


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("(On bowl_1)", "takes 2"),
        ("(Maybe bowl_1)", "unknown predicate"),
        ("(Not (On a b) (On a c))", "Not takes one"),
        ("(Or)", "is empty"),
        ("(And (On a b) x)", "expressions only"),
        ("(On a b) (On a c)", "after the expression"),
        ("(On a (b))", "names"),
        ("", "expected"),
    ],
)
def test_malformed_goals_are_one_clear_error(text, says):
    with pytest.raises(BddlError, match=says):
        parse_goal(text)


def test_a_registry_list_of_atoms_is_the_libero_conjunction_and_writes_back_identically():
    strings = ["(On bowl_1 plate_1)", "(Open cabinet_1_top_region)"]
    goal = goal_from_strings(strings)
    assert goal == conjunction([BOWL_ON_PLATE, OPEN_DRAWER])
    assert goal_strings(goal) == strings
    assert plain_atoms(goal) == (BOWL_ON_PLATE, OPEN_DRAWER)
    assert witness(goal) == (BOWL_ON_PLATE, OPEN_DRAWER)
    assert goal_strings(Then((Atom(OPEN_DRAWER), Atom(BOWL_ON_PLATE)))) == [
        "(Then (Open cabinet_1_top_region) (On bowl_1 plate_1))"
    ]
    negation = And((Or((Atom(BOWL_ON_RAMEKIN), Atom(BOWL_IN_DRAWER))), Not(Atom(BOWL_ON_PLATE))))
    for goal in (Then((Atom(OPEN_DRAWER), Atom(BOWL_ON_PLATE))), negation, conjunction([BOWL_ON_PLATE])):
        assert goal_from_strings(goal_strings(goal)) == goal  # what a generator writes is what loads
    with pytest.raises(BddlError, match="empty"):
        goal_from_strings([])


def test_negation_holds_on_any_other_receiver_and_never_on_the_negated_one():
    goal = And((Or((Atom(BOWL_ON_RAMEKIN), Atom(BOWL_IN_DRAWER))), Not(Atom(BOWL_ON_PLATE))))
    assert plain_atoms(goal) is None
    assert holds_now(goal, lambda p: p == BOWL_ON_RAMEKIN)
    assert holds_now(goal, lambda p: p == BOWL_IN_DRAWER)
    assert not holds_now(goal, lambda p: p == BOWL_ON_PLATE)  # the source task: a failure
    assert not holds_now(goal, lambda p: p in (BOWL_ON_PLATE, BOWL_ON_RAMEKIN))
    assert not holds_now(goal, lambda p: False)
    assert witness(goal) == (BOWL_ON_RAMEKIN,)
    assert atoms(goal) == (BOWL_ON_RAMEKIN, BOWL_IN_DRAWER, BOWL_ON_PLATE)


def test_then_succeeds_only_in_order():
    goal = Then((Atom(OPEN_DRAWER), Atom(BOWL_ON_PLATE)))
    in_order = [set(), {OPEN_DRAWER}, {OPEN_DRAWER}, {OPEN_DRAWER, BOWL_ON_PLATE}]
    assert run(goal, in_order) == [False, False, False, True]
    wrong_order = [set(), {BOWL_ON_PLATE}, {BOWL_ON_PLATE, OPEN_DRAWER}, {BOWL_ON_PLATE, OPEN_DRAWER}]
    assert run(goal, wrong_order) == [False, False, False, False]
    assert run(unordered(goal), wrong_order) == [False, False, True, True]  # right goals, wrong order
    same_step = [set(), {BOWL_ON_PLATE, OPEN_DRAWER}]
    assert run(goal, same_step) == [False, False]  # "before" is strict
    # the first time counts: doing B, undoing it, then A and B again is still the wrong order
    redo = [set(), {BOWL_ON_PLATE}, set(), {OPEN_DRAWER}, {OPEN_DRAWER, BOWL_ON_PLATE}]
    assert run(goal, redo) == [False] * 5
    # in order, but A undone by the end: not done
    undone = [set(), {OPEN_DRAWER}, {BOWL_ON_PLATE}]
    assert run(goal, undone) == [False, False, False]
    assert not holds_now(goal, lambda p: False) and holds_now(goal, lambda p: True)  # one state: order ignored


def test_then_of_compound_parts_uses_when_each_part_first_held():
    first = Or((Atom(BOWL_ON_RAMEKIN), Atom(BOWL_ON_PLATE)))
    goal = Then((first, Atom(OPEN_DRAWER)))
    assert run(goal, [set(), {BOWL_ON_PLATE}, {BOWL_ON_RAMEKIN, OPEN_DRAWER}]) == [False, False, True]
    progress = GoalProgress(goal)
    for step, true in enumerate([set(), {BOWL_ON_PLATE}, {BOWL_ON_RAMEKIN, OPEN_DRAWER}]):
        progress.observe(step, lambda p, true=true: p in true)
    assert progress.first_held == 2 and progress.first[first] == 1


def test_stages_give_the_order_a_policy_must_follow():
    goal = Then((Atom(OPEN_DRAWER), Atom(BOWL_ON_PLATE)))
    assert is_ordered(goal) and not is_ordered(unordered(goal))
    assert stages(goal) == ((OPEN_DRAWER,), (BOWL_ON_PLATE,))
    assert stages(And((goal, Not(Atom(BOWL_ON_RAMEKIN))))) == ((OPEN_DRAWER,), (BOWL_ON_PLATE,))
    assert stages(conjunction([BOWL_ON_PLATE, OPEN_DRAWER])) == ((BOWL_ON_PLATE, OPEN_DRAWER),)
    assert witness(goal) == (OPEN_DRAWER, BOWL_ON_PLATE)


def test_a_goal_whose_first_alternative_contradicts_it_has_no_witness():
    with pytest.raises(BddlError, match="no witness"):
        witness(And((Atom(BOWL_ON_PLATE), Not(Atom(BOWL_ON_PLATE)))))
    with pytest.raises(BddlError, match="no witness"):
        witness(Not(Atom(BOWL_ON_PLATE)))


def test_choices_resolve_each_alternative_first_parts_first_and_keep_negations():
    either = Or((Atom(BOWL_ON_RAMEKIN), Atom(BOWL_IN_DRAWER)))
    goal = And((either, Not(Or((Atom(BOWL_ON_PLATE), Atom(OPEN_DRAWER))))))
    found = list(choices(goal))
    # Each choice is the goal with its `Or` replaced by one part; the `Or` under `Not` stays (it is a ban).
    assert found == [
        And((Atom(BOWL_ON_RAMEKIN), goal.parts[1])),
        And((Atom(BOWL_IN_DRAWER), goal.parts[1])),
    ]
    assert stages(found[0]) == stages(goal)  # the first choice is the witness
    ordered = Then((Or((Atom(OPEN_DRAWER), Atom(BOWL_ON_RAMEKIN))), Atom(BOWL_ON_PLATE)))
    assert [stages(c) for c in choices(ordered)] == [
        ((OPEN_DRAWER,), (BOWL_ON_PLATE,)),
        ((BOWL_ON_RAMEKIN,), (BOWL_ON_PLATE,)),
    ]
    assert list(choices(Atom(BOWL_ON_PLATE))) == [Atom(BOWL_ON_PLATE)]


def test_plans_are_the_stages_of_the_choices_that_can_be_met():
    # the first choice contradicts the goal's ban (the bowl on the plate, and not on the plate)
    goal = And((Or((Atom(BOWL_ON_PLATE), Atom(BOWL_ON_RAMEKIN))), Not(Atom(BOWL_ON_PLATE))))
    assert list(plans(goal)) == [((BOWL_ON_RAMEKIN,),)]
    ordered = Then((Atom(OPEN_DRAWER), Atom(BOWL_ON_PLATE)))
    assert list(plans(ordered)) == [stages(ordered)]
    assert list(plans(And((Atom(BOWL_ON_PLATE), Not(Atom(BOWL_ON_PLATE)))))) == []


def test_moved_is_langgaps_own_atom_never_a_witness_nor_a_bddl_goal():
    from langgap.bddl import parse_bddl, rewrite_task_sections
    from langgap.stack import bddl_path

    text = "(And (Or (On bowl_1 stove_1) (Moved bowl_1)) (Not (On bowl_1 plate_1)))"
    goal = parse_goal(text)
    assert str(goal) == text and Predicate.of("moved", ["bowl_1"]) in atoms(goal)
    moved = Predicate.of("Moved", ["bowl_1"])
    assert not moved.libero and Predicate.of("On", ["bowl_1", "stove_1"]).libero
    with pytest.raises(BddlError, match="LIBERO does not evaluate Moved"):
        moved.as_libero()
    # the BDDL file states the first alternative; the oracle's plans leave the `Moved` choice out
    assert witness(goal) == (Predicate.of("On", ["bowl_1", "stove_1"]),)
    assert list(plans(goal)) == [((Predicate.of("On", ["bowl_1", "stove_1"]),),)]
    assert holds_now(goal, lambda p: p == moved)  # set down anywhere else: the goal holds
    assert not holds_now(goal, lambda p: p in (moved, Predicate.of("On", ["bowl_1", "plate_1"])))
    with pytest.raises(BddlError, match="LIBERO does not evaluate"):
        witness(parse_goal("(And (Moved bowl_1) (Not (On bowl_1 plate_1)))"))
    source = bddl_path("libero_spatial", "pick_up_the_black_bowl_on_the_stove_and_place_it_on_the_plate").read_text()
    stated = rewrite_task_sections(
        source,
        language="x",
        obj_of_interest=("akita_black_bowl_1",),
        goal=(Predicate.of("Moved", ["akita_black_bowl_1"]),),
    )
    with pytest.raises(BddlError, match="no BDDL file states it"):
        parse_bddl(stated)


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("((On a b))", r"^goal '\(\(On a b\)\)': expected '\(Name \.\.\.\)' at token 0$"),
        ("()", r"expected '\(Name \.\.\.\)' at token 0"),
        ("(And (", r"^goal '\(And \(': expected '\(Name \.\.\.\)' at token 2$"),
        ("(On", "an atom's arguments must be names, closed by"),
        ("(On a b", r"^goal '\(On a b': an atom's arguments must be names, closed by '\)'$"),
        ("(And (On a b)", r"^goal '\(And \(On a b\)': \(And \.\.\.\) takes expressions only, or lacks '\)'$"),
        ("(And (On a (b)))", r"^goal '\(And \(On a \(b\)\)\)': an atom's arguments"),
    ],
)
def test_a_malformed_goal_is_named_whole_with_where_it_breaks(text, says):
    with pytest.raises(BddlError, match=says):
        parse_goal(text)


def test_an_empty_registry_goal_is_one_error():
    with pytest.raises(BddlError, match="^goal is empty$"):
        goal_from_strings([])


def test_order_is_found_and_dropped_under_a_negation_too():
    a, b = Atom(Predicate.of("On", ["a", "b"])), Atom(Predicate.of("On", ["c", "d"]))
    assert is_ordered(Not(Then((a, b)))) and not is_ordered(Not(And((a, b))))
    assert unordered(Not(Then((a, b)))) == Not(And((a, b)))
    assert unordered(Or((Then((a, b)), a))) == Or((And((a, b)), a))
    assert unordered(Not(a)) == Not(a)


def test_a_witness_names_every_atom_libero_cannot_state():
    with pytest.raises(BddlError, match=r"its witness needs \(Moved a\), \(Moved b\), which LIBERO"):
        witness(parse_goal("(And (Moved a) (Moved b))"))


def test_the_unordered_parts_join_the_last_stage_of_the_order():
    goal = parse_goal("(And (Then (On a x) (On b x) (On c x)) (On d x))")
    assert [[str(p) for p in group] for group in stages(goal)] == [
        ["(On a x)"],
        ["(On b x)"],
        ["(On c x)", "(On d x)"],
    ]
    with pytest.raises(BddlError, match=r"^goal .*: more than one ordered part$"):
        stages(parse_goal("(And (Then (On a x) (On b x)) (Then (On c x) (On d x)))"))


def test_a_negation_is_followed_step_by_step_and_remembers_when_it_first_held():
    on = Predicate.of("On", ["a", "b"])
    progress = GoalProgress(Not(Atom(on)))
    assert [progress.observe(step, lambda p, held=held: held) for step, held in enumerate([True, False, True])] == [
        False,
        True,
        False,
    ]
    assert progress.first_held == 1
    # an order under a negation needs the first steps of its parts: evaluated with the step
    a, b = Predicate.of("On", ["a", "x"]), Predicate.of("On", ["b", "x"])
    progress = GoalProgress(Not(Then((Atom(a), Atom(b)))))
    assert progress.observe(0, lambda p: p == a)
    assert not progress.observe(1, lambda p: True)
    assert progress.first_held == 0
