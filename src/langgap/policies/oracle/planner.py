"""From a goal to one program of skills: order the sub-goals, then achieve each in turn.

The goal (`langgap.goals`) is met through one of its choices (each `Or` resolved to one part), the
choice with the fewest sub-goals still to achieve first (a skill each, drawer openings a closed
drawer implies counted; ties in the goal's order), and, within a choice, stage by stage
(`goals.stages`: the parts of a `Then` in order).
Within a stage, sub-goals that change a fixture's state come first (turn a knob, open a drawer —
also when a goal puts something into a closed drawer), then the pick-and-place ones in goal order,
then closing (put things in before shutting them). Each round skips what already holds; later rounds
retry what did not stick. When a choice ends without meeting the goal (a `Not` broken, a placement
that failed), the next choice is pursued from where the scene is.
"""

from __future__ import annotations

import numpy as np

from langgap import goals
from langgap.bddl import Predicate
from langgap.errors import LangGapError
from langgap.policies.oracle import drawer_press, drawers, hinges, pick_place, pushing
from langgap.policies.oracle.control import CLOSE, OPEN
from langgap.policies.oracle.grasps import has_grasp
from langgap.policies.oracle.motion import Agent, Program, actuate, back_off, hold
from langgap.policies.oracle.placement import spot_on_object, spots_aside, spots_in_region
from langgap.policies.oracle.predicates import holds, region_box
from langgap.policies.oracle.scene import Scene

ROUNDS = 3
_FIRST = ("Turnon", "Turnoff", "Open")
_LAST = ("Close",)
_STATE = {"Open": "open", "Close": "close", "Turnon": "on", "Turnoff": "off"}


class OracleError(LangGapError):
    """The oracle cannot act on this goal in this scene."""


def parse_goal(expressions: tuple[str, ...] | list[str]) -> goals.Goal:
    """Parse a goal given as registry expressions (`(On bowl_1 plate_1)`, `(Then ...)`: their conjunction);
    an empty or malformed goal is an OracleError."""
    if not expressions:
        raise OracleError("the oracle needs a goal, got none")
    try:
        return goals.goal_from_strings(expressions)
    except LangGapError as exc:
        raise OracleError(f"the oracle cannot read goal {list(expressions)}: {exc}") from None


def check_goal(scene: Scene, goal: tuple[Predicate, ...]) -> None:
    """Raise OracleError unless every predicate names things this scene has, in a role the oracle handles."""
    for predicate in goal:
        if not predicate.libero:  # `Moved`: what the oracle never aims at (`goals.plans` leaves it out)
            if not scene.has_entity(predicate.args[0]):
                raise OracleError(f"goal {predicate}: no object {predicate.args[0]!r} in this scene")
        elif predicate.name in ("On", "In"):
            obj, target = predicate.args
            if not scene.has_entity(obj):
                raise OracleError(f"goal {predicate}: no object {obj!r} in this scene")
            if not (scene.has_entity(target) or scene.has_region(target)):
                raise OracleError(f"goal {predicate}: no object or region {target!r} in this scene")
            if predicate.name == "In" and not scene.has_region(target):
                raise OracleError(f"goal {predicate}: `In` needs a region, {target!r} is an object")
        else:
            (name,) = predicate.args
            if name not in scene.articulated:
                raise OracleError(f"goal {predicate}: {name!r} is not an articulated part of this scene")
            if _STATE[predicate.name] not in scene.articulation(name).intervals:
                raise OracleError(f"goal {predicate}: {name!r} has no {_STATE[predicate.name]!r} state")


def order_goal(scene: Scene, goal: tuple[Predicate, ...]) -> list[Predicate]:
    """Sub-goals in the order to pursue them, with implied drawer openings inserted."""
    first = [p for p in goal if p.name in _FIRST]
    last = [p for p in goal if p.name in _LAST]
    middle = [p for p in goal if p.name not in _FIRST + _LAST]
    for p in middle:
        container = p.args[1]
        if container in scene.articulated and "open" in scene.articulation(container).intervals:
            opening = Predicate("Open", (container,))
            if opening not in first:
                first.append(opening)
    return first + middle + last


def _achieve(agent: Agent, predicate: Predicate, later: tuple[Predicate, ...] = ()) -> Program:
    """Pursue one sub-goal; `later` are the sub-goals pursued after it (a drawer opened first is
    cleared of what they will pick up from under it)."""
    scene = agent.scene
    name, args = predicate.name, predicate.args
    if name in ("On", "In"):
        obj, target = args
        if scene.has_entity(target):
            spots = [spot_on_object(scene, obj, target)]
        else:
            spots = spots_in_region(scene, obj, target, inside=name == "In")
            if spots[0].blockers and name == "On":
                # `On` a region needs contact with its surface: clear the way first.
                keep_clear = np.concatenate(region_box(scene.region(target), inside=False))
                for blocker in spots[0].blockers:
                    asides = spots_aside(agent.scene, blocker, keep_clear, then=agent.scene.pos(obj))
                    aside = (yield from pick_place.pick(agent, blocker, asides)) if asides else None
                    if aside is not None:
                        yield from pick_place.place(agent, blocker, aside)
                scene = agent.scene
                spots = spots_in_region(scene, obj, target, inside=False)
        if not has_grasp(scene, obj):
            return (yield from pushing.slide_to(agent, obj, spots[0]))
        spot = yield from pick_place.pick(agent, obj, spots)
        if spot is None:
            return False
        return (yield from pick_place.place(agent, obj, spot))
    (part,) = args
    art = scene.articulation(part)
    if name in ("Turnon", "Turnoff"):
        return (yield from hinges.turn(agent, part, _STATE[name]))
    if art.slide:
        if name == "Open":
            moved = tuple(dict.fromkeys(p.args[0] for p in later if p.name in ("On", "In")))
            yield from drawers.clear_sweep(agent, part, moved)
            return (yield from drawer_press.open_drawer(agent, part))
        return (yield from drawers.push_closed(agent, part))
    if name == "Close":
        return (yield from hinges.close_door(agent, part))
    raise OracleError(f"the oracle cannot {name.lower()} {part!r} (a hinged door)")


def _pursue(agent: Agent, atoms: tuple[Predicate, ...]) -> Program:
    """Rounds over the ordered sub-goals, each round skipping what already holds."""
    steps = order_goal(agent.scene, atoms)
    for _ in range(ROUNDS):
        pending = [p for p in steps if not holds(agent.scene, p)]
        if not pending:
            return
        for index, predicate in enumerate(pending):
            if not holds(agent.scene, predicate):
                yield from _achieve(agent, predicate, tuple(pending[index + 1 :]))


def _skills(scene: Scene, plan: tuple[tuple[Predicate, ...], ...]) -> int:
    """How many sub-goals of a choice's plan are still to achieve, with the openings they imply: each
    costs a skill of about a hundred steps, so the choice with fewer is done sooner."""
    return sum(not holds(scene, p) for stage in plan for p in order_goal(scene, stage))


def program(agent: Agent, goal: goals.Goal) -> Program:
    """The whole episode: pursue the goal choice by choice (fewest skills first), stage by stage, then
    hold still."""
    check_goal(agent.scene, goals.atoms(goal))
    planned = False
    for plan in sorted(goals.plans(goal), key=lambda plan: _skills(agent.scene, plan)):
        planned = True
        for stage in plan:
            yield from _pursue(agent, stage)
        if len(plan) > 1:
            # a later stage may have undone an earlier one; re-achieving it keeps the order (first times stay)
            yield from _pursue(agent, tuple(p for stage in plan for p in stage))
        if goals.holds_now(goal, lambda p: holds(agent.scene, p)):
            break
    if not planned:
        raise OracleError(f"the oracle cannot plan goal {goal}: every choice contradicts it or orders it twice")
    return (yield from hold(agent))


# A `keep_clear` box no spot falls into: a put-down only needs the table.
_NOWHERE = np.array([np.inf, np.inf, 0.0, np.inf, np.inf, 0.0])


def put_down(agent: Agent) -> Program:
    """Let go of what the hand holds, midway through another program: set it on the table aside from
    where it is (where no goal asks for it), else release it where it is; then lift the hand clear."""
    if agent.grip != CLOSE:
        return
    scene = agent.scene
    held = [e for e in scene.loose() if scene.touches_gripper(e)]
    spots = spots_aside(scene, held[0], _NOWHERE) if held else []
    if spots:
        yield from pick_place.place(agent, held[0], spots[0])
        return
    yield from actuate(agent, OPEN)
    yield from back_off(agent)


# The state an articulated part rests in (closed, off), the goal atom that restores it, and the one that leaves it.
_REST = {"close": ("Close", "Open"), "off": ("Turnoff", "Turnon")}
LEFT_REST = 0.1  # share of the way to the open (on) state a part must have moved to count as opened
OVERHANG_MARGIN = 0.02  # m: a place this close to beneath a part's footprint is under it


def opened_since(start: Scene, scene: Scene) -> list[tuple[str, str]]:
    """The articulated parts that were not open (on) in `start` and have since moved toward it by more than
    `LEFT_REST` of the way — what the episode so far opened or turned on, if only partly — each with the
    rest state (close, off) that undoes it. One name per part (a fixture's first joint is also listed under
    the fixture's name)."""
    found: list[tuple[str, str]] = []
    for name in scene.articulated:
        then, now = start.articulation(name), scene.articulation(name)
        for rest, (_, leave) in _REST.items():
            away = _STATE[leave]
            if rest not in now.intervals or away not in now.intervals or then.holds(away):
                continue
            travel = then.target(away) - then.qpos
            opened = bool(travel) and (now.qpos - then.qpos) / travel > LEFT_REST
            if opened and not any(_same_part(scene, name, other) for other, _ in found):
                found.append((name, rest))
    return found


def _same_part(scene: Scene, a: str, b: str) -> bool:
    """Whether two articulation names are one moving part (a fixture's name and its first joint's region)."""
    known = scene.articulated
    return a in known and b in known and np.array_equal(scene.raw[f"art/{a}/body"], scene.raw[f"art/{b}/body"])


def _negated(goal: goals.Goal) -> tuple[Predicate, ...]:
    """The atoms `goal` mentions inside a `Not`."""
    if isinstance(goal, goals.Not):
        return goals.atoms(goal.part)
    if isinstance(goal, goals.Atom):
        return ()
    return tuple(p for part in goal.parts for p in _negated(part))


def _reached_places(scene: Scene, predicate: Predicate) -> list[np.ndarray]:
    """Where the hand must go for `predicate`: the object it moves and its target, or the part's handle."""
    if predicate.name in ("On", "In"):
        obj, target = predicate.args
        places = [scene.pos(obj)]
        return places + [scene.pos(target) if scene.has_entity(target) else scene.region(target).pos]
    return [scene.articulation(predicate.args[0]).handle]


def needs_rest(scene: Scene, part: str, state: str, goal: goals.Goal) -> bool:
    """Whether `goal` needs the opened (turned-on) `part` back in its rest `state` before anything else: the
    goal negates its leaving that state, or — where the goal does not mention the part — the part as it
    sticks out now overhangs a place the goal's hand must reach (an open drawer above the one to open, or
    above an object to move)."""
    leave = _REST[state][1]
    if any(p.name == leave and _same_part(scene, p.args[0], part) for p in _negated(goal)):
        return True
    mentioned = goals.atoms(goal)
    if any(any(_same_part(scene, arg, part) for arg in p.args) for p in mentioned):
        return False  # the goal says what it wants of the part; its program sees to it
    box = scene.articulation(part).bbox
    lo, hi = box[:3] - OVERHANG_MARGIN, box[3:] + OVERHANG_MARGIN
    return any(
        bool(np.all(place[:2] >= lo[:2]) and np.all(place[:2] <= hi[:2]) and place[2] < box[2])
        for p in mentioned
        for place in _reached_places(scene, p)
    )


def replan(agent: Agent, goal: goals.Goal, start: Scene | None = None) -> Program:
    """A new goal midway through the episode (its instruction changed): put down what the hand holds, close
    (turn off) what the episode opened (turned on) since `start` — the scene as the episode began — where
    the new goal needs it (`needs_rest`), then the whole program for the new goal from the scene as it is."""
    yield from put_down(agent)
    for part, state in opened_since(start, agent.scene) if start is not None else ():
        if needs_rest(agent.scene, part, state, goal):
            yield from _achieve(agent, Predicate(_REST[state][0], (part,)))
    return (yield from program(agent, goal))
