"""The candidate goals of one source task, and how each relates to the source (its dimension).

A candidate is a one-predicate goal the source's scene affords (`affordances`): a pick-and-place
or an articulation. Left out: goals true at t0 by construction (handled in `affordances`) and, for
a conjunctive source (libero_10), its own conjuncts: doing the source task achieves them, so they
cannot tell whether the policy read its instruction.
"""

from __future__ import annotations

from langgap.bddl import BddlProblem, Predicate
from langgap.catalog import affordances


def candidate_goals(scene: BddlProblem, source_goal: tuple[Predicate, ...]) -> list[Predicate]:
    """One-predicate goals for tasks sharing `scene` with a source whose goal is `source_goal`.

    A single-predicate source's own goal is included (it is the original task).
    """
    goals = affordances.placements(scene) + affordances.articulations(scene)
    if len(source_goal) > 1:
        goals = [g for g in goals if g not in source_goal]
    return goals


def _action_class(predicate: Predicate) -> str:
    return "place" if not affordances.is_articulation(predicate) else predicate.name


def dimension(goal: Predicate, source_goal: tuple[Predicate, ...], scene: BddlProblem) -> str:
    """The paper's dimension of `goal` relative to its source's goal.

    Action type differs (open/close/turn on/off vs pick-and-place) -> drawer_action; else the acted-on
    object's category differs -> change_object; else another instance of the same category ->
    spatial_description; else the target differs -> change_target. Against a conjunctive source the
    closest conjunct of the same action type counts.
    """
    same_action = [p for p in source_goal if _action_class(p) == _action_class(goal)]
    if not same_action:
        return "drawer_action"
    subject = goal.args[0]
    if any(p.args[0] == subject for p in same_action):
        return "change_target"
    subject_category = affordances.category(subject, scene)
    if any(affordances.category(p.args[0], scene) == subject_category for p in same_action):
        return "spatial_description"
    return "change_object"


def obj_of_interest(goal: tuple[Predicate, ...], scene: BddlProblem) -> tuple[str, ...]:
    """The goal's entities in order, a region of an object standing for the object (`basket_1`), as LIBERO does."""
    out: list[str] = []
    for predicate in goal:
        for entity in predicate.args:
            region = affordances.region_of(entity, scene)
            name = region.target if region is not None and region.target in scene.objects else entity
            if name not in out:
                out.append(name)
    return tuple(out)
