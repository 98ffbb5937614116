"""Dragging a hollow object (a bowl, a plate) over the table by the closed fingers hooked inside it.

Lowered into the object and moved sideways, the fingers meet its inner wall and take it along:
no grasp, no release, and the hand needs no room beside the object, only above it. A *pressed* drag
(for what no grasp fits, e.g. a plate) aims the fingers below the object's floor all the way: held
down on the table, a plate's shallow rim cannot ride onto a low object in its way (a cream cheese
box), it pushes the object ahead instead, and its slope cannot lift the fingers out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.control import CLOSE
from langgap.policies.oracle.geometry import Boxes, depth, depth_across, hand_yaw, top_down, wrist_yaw
from langgap.policies.oracle.grasps import APPROACHES, PENETRATION_TOLERANCE, hand_boxes
from langgap.policies.oracle.motion import RETREAT, Agent, Program, move, reorient, stalled, travel
from langgap.policies.oracle.placement import flight_path
from langgap.policies.oracle.scene import Scene

HOOK_DEPTHS = (0.03, 0.025, 0.02, 0.015)  # fingertips below the object's top, deepest first
PRESSED_DEPTHS = (*HOOK_DEPTHS, 0.01)  # held down, the fingers stay in a shallower hollow (a plate's)
PRESS = 0.02  # a pressed drag aims the grip site this far below where the fingers went in
FLOOR_CLEARANCE = 0.005  # the fingertips stay this far above the object's lowest point
WALL_STEP = 0.005  # the fingers' way to the inner wall is measured in steps this long
WALL_SEARCH = 0.08
DRAG_OVERSHOOT = 0.01  # dragged this much further than asked: the fingers sit a little loose in the object
DRAG_SPEED = 0.6
DRAG_STEP = 0.03  # metres per step a pressed drag is aimed ahead of the hand
DRAG_STALL_STEPS, DRAG_STALL_PROGRESS = 8, 0.004  # a pressed drag that gains less over these steps stops
PATH_SAMPLES = (0.25, 0.5, 0.75, 1.0)
LOOSE_ALLOWANCE = 0.018  # how far the dragged object may run into another loose object (nudging it)


@dataclass(frozen=True)
class Hook:
    """A drag: the closing yaw of the top-down hand, where its grip site goes down into the object
    (touching nothing), where the drag ends, and how far the object runs into loose objects on its
    way (they get nudged); `pressed`: the fingers press the object onto the table all the way."""

    yaw: float
    start: np.ndarray
    end: np.ndarray
    nudge: float = 0.0
    pressed: bool = False


def _closed_hand(point: np.ndarray, yaw: float, sweep: float = 0.0) -> Boxes:
    return hand_boxes(point, yaw, width=0.0, sweep=sweep)


def _hits(boxes: Boxes, obstacles: Boxes) -> bool:
    return depth(boxes, obstacles) > PENETRATION_TOLERANCE


def plan_hook(scene: Scene, obj: str, shift: np.ndarray, *, pressed: bool = False) -> Hook | None:
    """How to drag `obj` by the horizontal `shift` with the fingers inside it, or None: it has no hollow
    the closed fingers fit into deep enough, or the hand or the object would hit a fixture on the
    way, or the object would run far into a loose one. A `pressed` drag pushes loose objects in the
    object's way ahead of it, so only fixtures stop it.

    The object's own walls are its oriented parts (its axis-aligned boxes fill a bowl's inside).
    """
    boxes, parts = scene.boxes(obj), scene.parts(obj)
    bounds = parts.aabb()
    top, lowest = float(bounds[:, 5].max()), float(bounds[:, 2].min())
    centre = (bounds[:, :2].min(axis=0) + bounds[:, 3:5].max(axis=0)) / 2.0
    distance = float(np.linalg.norm(shift))
    along = np.array([*(shift / distance), 0.0])
    fixed = scene.obstacles(exclude=(obj,), fixtures_only=True)
    loose = scene.loose_boxes(exclude=(obj,))
    moved = Boxes.concat([boxes.shifted(np.array([*(shift * t), 0.0])) for t in PATH_SAMPLES])
    # Measured across: how far it runs in, beyond where it stands already.
    nudge = max(0.0, depth_across(moved, loose) - max(0.0, depth_across(boxes, loose)))
    if _hits(moved, fixed) or (nudge > LOOSE_ALLOWANCE and not pressed):
        return None
    others = scene.obstacles(exclude=(obj,), fixtures_only=pressed)
    across = math.atan2(along[1], along[0]) + math.pi / 2
    current = hand_yaw(scene.eef_mat)
    # Palm across the drag first: it is thin along the way it moves.
    for yaw in (across, across + math.pi / 2):
        yaw = wrist_yaw(yaw, current, scene.azimuth(centre))
        for hook_depth in PRESSED_DEPTHS if pressed else HOOK_DEPTHS:
            grip = np.array([*centre, top - hook_depth + hand.TIP])
            if grip[2] - hand.TIP < lowest + FLOOR_CLEARANCE:
                continue
            lowered = _closed_hand(grip, yaw, sweep=APPROACHES[0] + hook_depth)
            if _hits(lowered, parts) or _hits(lowered, others):
                continue
            end = grip + along * (_to_wall(parts, grip, yaw, along) + distance + DRAG_OVERSHOOT)
            on_way = Boxes.concat([_closed_hand(grip + (end - grip) * t, yaw) for t in PATH_SAMPLES])
            if not _hits(on_way, others):
                return Hook(yaw=yaw, start=grip, end=end, nudge=nudge, pressed=pressed)
    return None


def _to_wall(parts: Boxes, grip: np.ndarray, yaw: float, along: np.ndarray) -> float:
    """How far the closed fingers at `grip` move along `along` before they touch the object's wall."""
    for travelled in np.arange(WALL_STEP, WALL_SEARCH + 1e-9, WALL_STEP):
        if _hits(_closed_hand(grip + along * travelled, yaw), parts):
            return float(travelled - WALL_STEP)
    return WALL_SEARCH


def drag(agent: Agent, hook: Hook) -> Program:
    """Lower the closed fingers into the object, drag it along the hook's way, lift the hand out."""
    rot = top_down(hook.yaw)
    above = hook.start + np.array([0.0, 0.0, APPROACHES[0]])
    yield from reorient(agent, rot, toward=above)
    path = flight_path(agent.scene, agent.scene.eef_pos, above, hang=hand.TIP, reach=hand.REACH)
    yield from travel(agent, above, path=path, rot=rot, grip=CLOSE, tol=0.01)
    yield from move(agent, hook.start, tol=0.006, steps=30, speed=0.6)
    if hook.pressed:
        reached = yield from _pressed_drag(agent, hook)
    else:
        reached = yield from move(agent, hook.end, tol=0.01, steps=40, speed=DRAG_SPEED, level=True)
    # Out of the object, high enough for the hand to turn freely above it.
    lift = agent.scene.eef_pos + np.array([0.0, 0.0, RETREAT])
    yield from move(agent, lift, tol=0.02, steps=15, through=True)
    return reached


def _pressed_drag(agent: Agent, hook: Hook, *, tol: float = 0.006, steps: int = 60) -> Program:
    """Drag along the hook's way with the grip site aimed `PRESS` below where it went in, until the
    hand is within `tol` of the way's end (horizontally: pressing, it never gets down there) or stalls."""
    low = hook.start[2] - PRESS
    history: list[float] = []
    for _ in range(steps):
        error = hook.end[:2] - agent.scene.eef_pos[:2]
        distance = float(np.linalg.norm(error))
        if distance < tol:
            return True
        history.append(distance)
        if stalled(history, DRAG_STALL_STEPS, DRAG_STALL_PROGRESS):
            return False
        ahead = agent.scene.eef_pos[:2] + error * min(1.0, DRAG_STEP / distance)
        yield agent.command(np.array([*ahead, low]), speed=DRAG_SPEED)
    return False
