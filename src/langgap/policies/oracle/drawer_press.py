"""Opening a drawer whose handle no grasp can hold: the closed fingers pressed on or behind the bar and
pulled along the drawer's axis (a *pressed drag*); and the choice between that and a grasp.

A bottom drawer's handle bar sits 61 mm under the next drawer's handle: a hand closing across it meets
that handle or the table wherever it comes from. Closed, the fingers form a flat blade that fits into
the slot between the two handles; slid in over the bar until their tips are behind it, pressed down
and pulled, they take the drawer along — a hook where the tips drop behind the bar, a pressed friction
drag on its top where they cannot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.control import CLOSE
from langgap.policies.oracle.drawers import (
    HANDLE_APPROACH,
    WRIST_OFFSET,
    drawer_front,
    handle_parts,
    opening_direction,
    opening_travel,
    pull_open,
)
from langgap.policies.oracle.geometry import Boxes, boxes_hit, rotation_about
from langgap.policies.oracle.grasps import PENETRATION_TOLERANCE, REACH_WEIGHT
from langgap.policies.oracle.motion import START_ROT, Agent, Program, actuate, move, reorient, stalled, travel
from langgap.policies.oracle.placement import flight_path
from langgap.policies.oracle.scene import Scene

# The room a hand closing across a handle bar needs above the bar's middle: half the open pads' gap, a
# finger, and 8 mm for the real fingers' meshes, which reach beyond their boxes (the hand closing on
# goal/s0's bottom bar, 61 mm under the next handle, never held it on 50 init states).
GRASP_SPAN = hand.PAD_GAP_OPEN / 2 + hand.FINGER_THICKNESS + 0.008
TIP_BEHIND = 0.008  # a pressed drag puts the fingertips this far behind the handle bar
SLOT_CLEARANCE = 0.004  # the fingers slide in this far above the bar's top
PRESS_DEPTH = 0.025  # then the hand is aimed this far below where it went in
PRESS_TILTS = tuple(math.radians(a) for a in (45, 55, 35))  # the fingers pointing down toward the bar
PRESS_TURNS = tuple(math.radians(a) for a in (0, 20, -20))  # the approach turned about the vertical
PRESS_TRIES = 3
PRESS_REACH = 0.75  # horizontal distance from the base beyond which the wrist, pulling, nears the arm's reach
TURN_COST = 0.5  # per radian the approach is turned from the drawer's axis
PULL_STEP = 0.03
PULL_SPEED = 0.6
PRESS_PROGRESS = 0.01  # a pull that moved the drawer less than this did not hold it


@dataclass(frozen=True)
class Press:
    """A pressed drag: the closed hand's frame, where it slides in to over the bar (straight in along the
    drawer's axis from `entry`), and its cost."""

    rot: np.ndarray
    grip: np.ndarray
    entry: np.ndarray
    cost: float


def _pressing(approach: np.ndarray, axis: np.ndarray, tilt: float, turn: float) -> np.ndarray:
    """A gripper frame pointing along the horizontal `approach` turned `turn` radians about the vertical
    and tilted `tilt` radians down, its fingers closing along the horizontal `axis` (the handle bar's)
    turned with it: closed, they form a flat blade that fits between two handles. Of the two such
    frames the one nearer the start's is used."""
    up = np.array([0.0, 0.0, 1.0])
    turning = rotation_about(up, turn)
    z = math.cos(tilt) * (turning @ approach) - math.sin(tilt) * up
    candidates = [np.stack([x, np.cross(z, x), z], axis=1) for x in (turning @ axis, -(turning @ axis))]
    return min(candidates, key=lambda rot: np.linalg.norm(rot - START_ROT))


def plan_presses(agent: Agent, region: str) -> list[Press]:
    """The pressed drags to try, best first: the fingers' deepest point ends `TIP_BEHIND` behind the
    handle bar at its middle, their lowest point `SLOT_CLEARANCE` above its top. Those whose fingers would
    meet something there are left out; a straight pull is preferred unless it stretches the arm (the
    hand follows the drawer out); among equals, the first tilt listed. The agent's drawer skill may fix the
    tilt and the turn."""
    art = agent.scene.articulation(region)
    direction = opening_direction(art)
    face, axis, _ = drawer_front(art, direction)
    _, bar = handle_parts(art, direction)
    top = float(art.boxes.select(bar).aabb()[:, 5].max())
    up = np.array([0.0, 0.0, 1.0])
    obstacles = agent.scene.obstacles()
    skill = agent.drawer
    presses = []
    for tilt in PRESS_TILTS if skill.tilt is None else (skill.tilt,):
        for turn in PRESS_TURNS if skill.turn is None else (skill.turn,):
            rot = _pressing(-direction, axis, tilt, turn)
            # Placed by the fingers' deepest point along the drawer's axis and their lowest point.
            fingers = Boxes.from_local(hand.finger_boxes(0.0), rot, art.handle)
            deepest = np.min(fingers.centre @ direction - fingers.extent(direction))
            lowest = np.min(fingers.centre[:, 2] - fingers.extent(up))
            grip = art.handle + direction * (face - TIP_BEHIND - deepest) + up * (top + SLOT_CLEARANCE - lowest)
            if boxes_hit(fingers.shifted(grip - art.handle), obstacles, PENETRATION_TOLERANCE):
                continue
            pulled = grip + opening_travel(art) - rot[:, 2] * WRIST_OFFSET
            cost = REACH_WEIGHT * max(0.0, agent.scene.reach(pulled) - PRESS_REACH) + TURN_COST * abs(turn)
            presses.append(Press(rot, grip, grip + HANDLE_APPROACH * direction, cost))
    return sorted(presses, key=lambda press: press.cost)  # stable: among equals, the first tilt listed


def press_open(agent: Agent, region: str) -> Program:
    """Open a drawer no grasp can hold: the closed fingers slide in over its handle bar, press down
    behind it and pull the drawer out along its axis (a hook where the tips drop behind the bar, a
    pressed friction drag on its top where they cannot)."""
    way = 0
    for _ in range(PRESS_TRIES):
        art = agent.scene.articulation(region)
        direction = opening_direction(art)
        presses = plan_presses(agent, region)
        if way >= len(presses):
            break
        press, start = presses[way], art.qpos
        yield from actuate(agent, CLOSE, max_steps=8)
        yield from reorient(agent, press.rot, toward=press.entry)
        path = flight_path(agent.scene, agent.scene.eef_pos, press.entry, hang=hand.TIP, reach=hand.REACH)
        yield from travel(agent, press.entry, path=path, rot=press.rot, grip=CLOSE, tol=0.008)
        yield from move(agent, press.grip, tol=0.005, steps=40, speed=0.5, level=True)
        pressed = press.grip - np.array([0.0, 0.0, agent.drawer.depth or PRESS_DEPTH])
        yield from move(agent, pressed, tol=0.003, steps=8, speed=0.5)
        goal = art.target("open")
        history: list[float] = []
        for _ in range(100):
            art = agent.scene.articulation(region)
            history.append(abs(goal - art.qpos))
            if art.reached("open") or stalled(history):
                break
            target = agent.scene.eef_pos + direction * PULL_STEP
            target[2] = pressed[2]
            # At full speed to the end: the open state reaches the joint's limit, and a drawer let slide
            # on covers the last millimetres a stretched arm cannot.
            yield agent.command(target, speed=PULL_SPEED)
        yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, 0.03]) + 0.03 * direction, tol=0.01, steps=15)
        if agent.scene.articulation(region).holds("open"):
            return True
        if room_above_handle(agent.scene, region) >= GRASP_SPAN:
            return (yield from pull_open(agent, region))  # drawn out from under the handle above: grasp it
        if abs(agent.scene.articulation(region).qpos - start) < PRESS_PROGRESS:
            way += 1  # that way in did not take the drawer along: try the next, from where the drawer stands
    return False


def open_drawer(agent: Agent, region: str) -> Program:
    """Open a drawer: by its handle where a grasp of the bar fits (`pull_open`), else by a pressed drag
    (`press_open`: a bottom drawer's bar sits too low over the table and too close under the next
    handle for the fingers to close around it)."""
    mode = agent.drawer.mode
    if mode == "grasp" or (mode == "auto" and room_above_handle(agent.scene, region) >= GRASP_SPAN):
        return (yield from pull_open(agent, region))
    return (yield from press_open(agent, region))


def room_above_handle(scene: Scene, region: str) -> float:
    """Height from a drawer's handle bar's middle to the lowest thing above the bar (another drawer's
    handle; inf: nothing): the room the upper finger of a hand closing across the bar has. Footprints
    are compared in the drawer's own frame (a cabinet standing turned has no axis-aligned bounds)."""
    art = scene.articulation(region)
    direction = opening_direction(art)
    _, bar = handle_parts(art, direction)
    bar_boxes, others = art.boxes.select(bar), scene.obstacles(exclude=(region,))
    over = np.ones(len(others), dtype=bool)
    for along in (direction, np.cross([0.0, 0.0, 1.0], direction)):
        lo = np.min(bar_boxes.centre @ along - bar_boxes.extent(along))
        hi = np.max(bar_boxes.centre @ along + bar_boxes.extent(along))
        over &= (others.centre @ along - others.extent(along) < hi) & (
            others.centre @ along + others.extent(along) > lo
        )
    bottoms = others.aabb()[:, 2]
    over &= bottoms >= bar_boxes.aabb()[:, 5].max()
    return float(bottoms[over].min() - art.handle[2]) if over.any() else np.inf
