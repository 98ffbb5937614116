"""Drawers: pulling one open by its handle, pushing one shut."""

from __future__ import annotations

import math

import numpy as np

from langgap.policies.oracle import hand, hooking
from langgap.policies.oracle.control import CLOSE, OPEN
from langgap.policies.oracle.geometry import (
    Boxes,
    boxes_hit,
    depth,
    hand_yaw,
    leaning,
    top_down,
    wrap_half_turn,
)
from langgap.policies.oracle.grasps import PENETRATION_TOLERANCE, REACH_WEIGHT, hand_hits, plan_grasp
from langgap.policies.oracle.motion import (
    START_ROT,
    Agent,
    Program,
    actuate,
    back_off,
    move,
    reorient,
    travel,
)
from langgap.policies.oracle.placement import flight_path
from langgap.policies.oracle.scene import Articulation

HANDLE_APPROACH = 0.07  # the hand slides this far onto a drawer's handle
HANDLE_HALF_HEIGHT = 0.008
WRIST_OFFSET = 0.15  # the wrist is this far behind the grip site
WRIST_REACH = 0.6  # horizontal distance from the base beyond which the wrist nears the arm's reach
SIDE_ANGLES = (0.0, math.radians(15), math.radians(30))
LOOSE_WEIGHT = 300.0  # cost per metre the hand would push into a loose object
LOOSE_ALLOWANCE = 0.006
PUSH_BESIDE = 0.03  # a drawer is pushed this far beside its handle
PUSH_LEAN = 0.6  # radians the fingers lean toward a push
SWEEP_MARGIN = 0.02  # an object is dragged this far clear of where an opening drawer will stand
SWEEP_DIRECTIONS = 16
NUDGE_COST = 3.0  # metres of drag worth one metre less of pushing into another loose object


def opening_direction(art: Articulation) -> np.ndarray:
    """Horizontal unit vector a slide joint's part travels along when it opens."""
    sign = np.sign(art.intervals["open"].mean() - art.intervals["close"].mean())
    direction = sign * art.axis * np.sign(art.limits[1] - art.limits[0])
    direction = np.array([direction[0], direction[1], 0.0])
    return direction / np.linalg.norm(direction)


def _pointing(approach: np.ndarray) -> np.ndarray:
    """A gripper frame pointing along `approach` (horizontal) with its fingers closing vertically.

    Of the two such frames (a parallel gripper is symmetric) the one nearer the hand's start is
    used: the wrist can turn to it from there. (From a hand turned by an earlier grasp, the frame
    nearer that hand can lie beyond the wrist's range: its last joints stall at their limits.)
    """
    candidates = []
    for up in (1.0, -1.0):
        x = np.array([0.0, 0.0, up])
        candidates.append(np.stack([x, np.cross(approach, x), approach], axis=1))
    return min(candidates, key=lambda rot: np.linalg.norm(rot - START_ROT))


def _handle_grasp(agent: Agent, art: Articulation, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How to take a drawer's handle bar with the fingers closing across it vertically: (rot, grasp, approach).

    From the front, or along the bar from either end (the hand then stays beside the drawer, and
    the wrist nearer the robot when the cabinet faces sideways). The clear option that least
    stretches the arm wins.
    """
    _, axis, half_length = drawer_front(art, direction)
    options = [(-direction, art.handle + hand.PAD_CENTRE * direction)]
    for side in (1.0, -1.0):
        along = side * axis  # the fingers slide onto the bar from its end
        grasp = art.handle - along * (half_length + hand.PAD_CENTRE - hand.PAD_HALF_HEIGHT)
        for angle in SIDE_ANGLES:  # turned away from the drawer's face, to keep the hand clear of the cabinet
            options.append((np.cos(angle) * along - np.sin(angle) * direction, grasp))
    fixed = agent.scene.obstacles(fixtures_only=True)
    loose = agent.scene.loose_boxes()
    local = hand.local_boxes(hand.PAD_GAP_OPEN)
    best, best_cost = None, np.inf
    for approach, grasp in options:
        rot = _pointing(approach)
        ready = grasp - HANDLE_APPROACH * approach
        # The hand at the grasp, where it starts sliding onto the bar, and on its way down there.
        poses = [grasp, ready] + [ready + np.array([0.0, 0.0, lift]) for lift in (0.05, 0.1, 0.15)]
        hands = Boxes.concat([Boxes.from_local(local, rot, pose) for pose in poses])
        arm = Boxes.concat([Boxes.from_local(hand.FOREARM, rot, pose) for pose in poses[1:]])
        cost = REACH_WEIGHT * max(0.0, agent.scene.reach(grasp - approach * WRIST_OFFSET) - WRIST_REACH)
        cost += 10.0 * boxes_hit(hands, fixed, PENETRATION_TOLERANCE)
        # Brushing a loose object with the hand is acceptable; ramming one (a bottle beside the cabinet)
        # is not, and the arm behind the hand knocks over whatever it meets.
        cost += LOOSE_WEIGHT * max(0.0, depth(hands, loose) - LOOSE_ALLOWANCE, depth(arm, loose))
        if cost < best_cost:
            best, best_cost = (rot, grasp, approach), cost
    return best


def opening_travel(art: Articulation) -> np.ndarray:
    """How far (a world vector) the drawer's front moves when it is pulled open."""
    return abs(art.target("open") - art.qpos) * opening_direction(art)


def opened_bounds(art: Articulation) -> np.ndarray:
    """The world bounds (lo xyz, hi xyz) the drawer will occupy once pulled open."""
    bounds = art.boxes.aabb()
    return np.concatenate([bounds[:, :3].min(axis=0), bounds[:, 3:].max(axis=0)]) + np.tile(opening_travel(art), 2)


def _exit_distance(box: np.ndarray, keep_clear: np.ndarray, along: np.ndarray) -> float:
    """How far the footprint of `box` must move along the horizontal unit vector `along` to leave the
    rectangle `keep_clear` (x/y lo, x/y hi)."""
    out = np.inf
    for axis in (0, 1):
        if along[axis] > 1e-9:
            out = min(out, (keep_clear[axis + 2] - box[axis]) / along[axis])
        elif along[axis] < -1e-9:
            out = min(out, (box[axis + 3] - keep_clear[axis]) / -along[axis])
    return float(max(out, 0.0))


def clear_sweep(agent: Agent, region: str, objects: tuple[str, ...]) -> Program:
    """Before a drawer is pulled open, drag each of `objects` that the open drawer would stand over out
    of its way (a bowl in front of the cabinet: once covered, no hand reaches it under the drawer).

    Each goes the shortest way out of the drawer's footprint (and `SWEEP_MARGIN` beyond) along which
    the hand can drag it; one that cannot be dragged stays.
    """
    scene = agent.scene
    art = scene.articulation(region)
    opened = opened_bounds(art)
    keep_clear = opened[[0, 1, 3, 4]] + np.array([-1.0, -1.0, 1.0, 1.0]) * SWEEP_MARGIN
    for obj in objects:
        scene = agent.scene
        box = scene.bbox(obj)
        beside = np.any(box[3:5] <= keep_clear[:2]) or np.any(box[:2] >= keep_clear[2:])
        if not scene.movable(obj) or beside or box[2] >= opened[5]:
            continue
        # Under the open drawer but still within reach of a hand coming straight down: leave it.
        grasp = plan_grasp(scene.with_part_moved(region, opening_travel(art)), obj)
        if grasp is not None and len(grasp.entry) == 1:
            continue
        hooks = []
        for k in range(SWEEP_DIRECTIONS):
            angle = 2 * math.pi * k / SWEEP_DIRECTIONS
            along = np.array([math.cos(angle), math.sin(angle)])
            distance = _exit_distance(box, keep_clear, along)
            hook = hooking.plan_hook(scene, obj, along * distance)
            if hook is not None:
                hooks.append((distance + NUDGE_COST * hook.nudge, hook))
        if hooks:
            yield from hooking.drag(agent, min(hooks, key=lambda item: item[0])[1])
    return True


def pull_open(agent: Agent, region: str) -> Program:
    """Open a drawer: take its handle bar with the fingers closing vertically, pull it out."""
    art = agent.scene.articulation(region)
    direction = opening_direction(art)
    rot, grasp, approach = _handle_grasp(agent, art, direction)
    ready = grasp - HANDLE_APPROACH * approach
    yield from reorient(agent, rot, toward=ready)
    path = flight_path(agent.scene, agent.scene.eef_pos, ready, hang=hand.PALM_HALF_LENGTH, reach=hand.REACH)
    yield from travel(agent, ready, path=path, rot=rot, grip=OPEN, tol=0.01)
    # Level: sagging on the way, the lower finger catches the front of the drawer below (goal/s3's top drawer).
    yield from move(agent, grasp, tol=0.006, steps=40, speed=0.5, level=True)
    yield from actuate(agent, CLOSE)
    goal = art.target("open")
    start = art.qpos
    held = agent.scene.eef_pos - art.handle
    for _ in range(80):
        art = agent.scene.articulation(region)
        left = (goal - art.qpos) / (goal - start)
        if left <= 0.03:
            break
        target = art.handle + (goal - art.qpos) * art.axis + held
        # Slow down near the goal so the drawer does not slide on past it.
        speed = float(np.clip(abs(goal - art.qpos) / 0.03, 0.15, 0.6))
        yield agent.command(target, speed=speed)
    yield from move(agent, agent.scene.eef_pos, tol=0.002, steps=3)  # let the drawer stop with the hand
    yield from actuate(agent, OPEN)
    yield from move(agent, agent.scene.eef_pos - 0.06 * approach + 0.03 * direction, tol=0.02, steps=20)
    return agent.scene.articulation(region).holds("open")


HANDLE_BAND = 0.01  # parts reaching within this of a drawer's outermost point form its handle bar


def handle_parts(art: Articulation, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How far each part of a drawer reaches along `direction`, and which parts form its handle bar."""
    reach = art.boxes.centre @ direction + art.boxes.extent(direction)
    return reach, reach >= reach.max() - HANDLE_BAND


def drawer_front(art: Articulation, direction: np.ndarray) -> tuple[float, np.ndarray, float]:
    """A drawer's front: the face's reach along `direction`, the handle bar's axis and its half-length."""
    boxes = art.boxes
    reach, handle = handle_parts(art, direction)
    face = float(reach[~handle].max()) if (~handle).any() else float(reach.max())
    axis = np.cross([0.0, 0.0, 1.0], direction)
    extent = boxes.centre[handle] @ axis
    half = boxes.extent(axis)[handle]
    centre = art.handle @ axis
    half_length = float(max(np.max(extent + half) - centre, centre - np.min(extent - half)))
    return face, axis, half_length


def push_closed(agent: Agent, region: str) -> Program:
    """Close a drawer by pushing its front, beside the handle, with the closed fingers."""
    art = agent.scene.articulation(region)
    direction = opening_direction(art)
    face, axis, half_length = drawer_front(art, direction)
    yaw = wrap_half_turn(math.atan2(axis[1], axis[0]), hand_yaw(agent.scene.eef_mat))
    rot = top_down(yaw)
    # On the handle (finger tips below the bar so they cannot slip over it) or beside it, wherever
    # the hand meets nothing else from the start to the end of the push; nearer the base is better.
    obstacles = agent.scene.obstacles(exclude=(region,))
    travel_in = (art.target("close") - art.qpos) * art.axis
    best, best_cost = None, np.inf
    for offset in (0.0, half_length + PUSH_BESIDE, -half_length - PUSH_BESIDE):
        point = art.handle + offset * axis
        contact = point + direction * (face - point @ direction + hand.FINGER_DEPTH + 0.008)
        if offset == 0.0:
            contact = point + direction * (art.handle @ direction - point @ direction + hand.FINGER_DEPTH + 0.016)
        contact[2] = art.handle[2] - HANDLE_HALF_HEIGHT - 0.004 + hand.TIP
        clash = sum(hand_hits(contact + t * travel_in, yaw, obstacles) for t in (0.0, 0.5, 1.0))
        cost = clash + agent.scene.reach(contact)
        if cost < best_cost:
            best, best_cost = contact, cost
    contact = best
    # Fingers leaning toward the push keep the wrist and forearm back from the cabinet's front.
    rot = leaning(rot, -direction, PUSH_LEAN)
    yield from actuate(agent, CLOSE, max_steps=8)
    yield from reorient(agent, rot, toward=contact)
    above = contact + np.array([0.0, 0.0, 0.05])
    path = flight_path(agent.scene, agent.scene.eef_pos, above, hang=hand.TIP, reach=hand.REACH)
    yield from travel(agent, contact, path=path, rot=rot, grip=CLOSE, tol=0.01)
    for _ in range(60):
        art = agent.scene.articulation(region)
        if art.reached("close"):
            break
        target = agent.scene.eef_pos - direction * 0.03
        target[2] = contact[2]
        yield agent.command(target, speed=0.6)
    yield from back_off(agent, away=direction * 0.03)
    return agent.scene.articulation(region).holds("close")
