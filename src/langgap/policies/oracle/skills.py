"""Skills: pick, place, pull or push a drawer, turn a knob, push an object, close a door.

Each skill is a program (see `motion`) that reads the scene afresh at every step, so it follows
objects that move, and returns whether it believes it succeeded; the planner verifies and retries.
"""

from __future__ import annotations

import math

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.control import CLOSE, OPEN
from langgap.policies.oracle.geometry import closing_yaw, rotation_about, top_down, wrap_half_turn
from langgap.policies.oracle.grasps import plan_grasp
from langgap.policies.oracle.motion import PASS_TOLERANCE, Agent, Program, actuate, move, reorient, travel
from langgap.policies.oracle.placement import Spot, flight_path, footprint_at

APPROACH = 0.08  # pre-grasp height above the grasp point
LIFT = 0.08  # lift after grasping before flying
GRASP_TOLERANCE = 0.005
LIFTED = 0.02  # an object that rose this much with the hand is held
RETREAT = 0.08
PLACE_CLEARANCE = 0.03  # released objects are lowered from this high above the support
PLACE_SPEED = 0.35
PICK_ATTEMPTS = 3
PLACE_STALL = 5  # steps without descending after which the load is released where it is
HAND_REACH = 0.06  # how far the open fingers reach sideways from the grip site


def _hang(agent: Agent, obj: str) -> float:
    """How far the held object reaches below the grip site."""
    return float(agent.scene.eef_pos[2] - agent.scene.bbox(obj)[2])


def pick(agent: Agent, obj: str, spot: Spot | None = None) -> Program:
    """Grasp `obj` from above and lift it; `spot` (where it will go) steers the grasp choice."""
    for _ in range(PICK_ATTEMPTS):
        scene = agent.scene
        shift = place_obstacles = None
        if spot is not None:
            shift = footprint_at(scene, obj, spot.xy, spot.support).centre[0] - scene.boxes(obj).centre[0]
            place_obstacles = scene.obstacles(exclude=(obj,))
        grasp = plan_grasp(scene, obj, place_shift=shift, place_obstacles=place_obstacles, approach=APPROACH)
        if grasp is None:
            return False
        first = grasp.entry[0]
        yield from reorient(agent, grasp.rot)
        path = flight_path(agent.scene, agent.scene.eef_pos, first, hang=hand.TIP, reach=HAND_REACH)
        yield from travel(agent, first, path=path, rot=grasp.rot, grip=OPEN, tol=0.01)
        for waypoint in grasp.entry[1:]:
            yield from move(agent, waypoint, tol=0.01, steps=30, speed=0.6)
        start_z = agent.scene.pos(obj)[2]
        yield from move(agent, grasp.point, tol=GRASP_TOLERANCE, steps=40, speed=0.5)
        yield from actuate(agent, CLOSE)
        lift_to = agent.scene.eef_pos + np.array([0.0, 0.0, LIFT])
        yield from move(agent, lift_to, tol=0.015, steps=30, speed=0.6)
        if agent.scene.touches_gripper(obj) and agent.scene.pos(obj)[2] - start_z > LIFTED:
            return True
        yield from actuate(agent, OPEN)
        yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, 0.05]), tol=0.015, steps=15)
    return False


def place(agent: Agent, obj: str, spot: Spot) -> Program:
    """Carry the held `obj` over `spot`, lower it until it touches down, release it and back off."""
    scene = agent.scene
    hang = _hang(agent, obj)
    offset = scene.eef_pos - scene.pos(obj)
    goal_xy = spot.xy + offset[:2]
    above_z = spot.support + hang + PLACE_CLEARANCE
    reach = float(np.max(np.abs(scene.bbox(obj)[:2] - scene.pos(obj)[:2]))) + 0.02
    above = np.array([*goal_xy, above_z])
    footprint = scene.bbox(obj)[[0, 1, 3, 4]] + np.array([-0.01, -0.01, 0.01, 0.01])
    path = flight_path(scene, scene.eef_pos, above, exclude=(obj,), hang=hang, reach=reach, footprint=footprint)
    yield from travel(agent, above, path=path, tol=0.012)
    floor = spot.support + hang
    heights: list[float] = []
    for _ in range(60):
        scene = agent.scene
        if not scene.touches_gripper(obj):
            break  # dropped on the way: let it be
        if scene.eef_pos[2] <= floor + 0.002 or (scene.touches_other(obj) and scene.eef_pos[2] < above_z - 0.01):
            break
        heights.append(float(scene.eef_pos[2]))
        if len(heights) > PLACE_STALL and heights[-PLACE_STALL - 1] - heights[-1] < 0.002:
            break  # the hand rests on something (a basket's rim): release from here
        correction = spot.xy - scene.pos(obj)[:2]
        target = np.array([*(scene.eef_pos[:2] + correction), floor - 0.01])
        yield agent.command(target, speed=PLACE_SPEED)
    yield from actuate(agent, OPEN, min_steps=5)
    yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, RETREAT]), tol=0.02, steps=20)
    return True


def _opening_direction(art) -> np.ndarray:
    """Horizontal unit vector a slide joint's part travels along when it opens."""
    sign = np.sign(art.intervals["open"].mean() - art.intervals["close"].mean())
    direction = sign * art.axis * np.sign(art.limits[1] - art.limits[0])
    direction = np.array([direction[0], direction[1], 0.0])
    return direction / np.linalg.norm(direction)


def _facing(direction: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """A gripper frame pointing against `direction` (horizontal) with its fingers closing vertically.

    Of the two such frames (a parallel gripper is symmetric) the one nearer `reference` is used,
    which keeps the wrist within its joint limits when turning from a top-down pose.
    """
    approach = -direction
    candidates = []
    for up in (1.0, -1.0):
        x = np.array([0.0, 0.0, up])
        y = np.cross(approach, x)
        candidates.append(np.stack([x, y, approach], axis=1))
    return min(candidates, key=lambda rot: np.linalg.norm(rot - reference))


def pull_open(agent: Agent, region: str) -> Program:
    """Open a drawer: grasp its handle from the front with the fingers closing vertically, pull."""
    art = agent.scene.articulation(region)
    direction = _opening_direction(art)
    rot = _facing(direction, agent.scene.eef_mat)
    grasp = art.handle + hand.PAD_CENTRE * direction
    front = grasp + 0.10 * direction
    yield from reorient(agent, rot)
    path = flight_path(agent.scene, agent.scene.eef_pos, front, hang=hand.PALM_HALF_LENGTH, reach=HAND_REACH)
    yield from travel(agent, front, path=path, rot=rot, grip=OPEN, tol=0.01)
    yield from move(agent, grasp, tol=0.006, steps=40, speed=0.5)
    yield from actuate(agent, CLOSE)
    goal = art.target("open")
    start = art.qpos
    for _ in range(80):
        art = agent.scene.articulation(region)
        left = (goal - art.qpos) / (goal - start)
        if left <= 0.03:
            break
        target = art.handle + (goal - art.qpos) * art.axis + hand.PAD_CENTRE * direction
        # Slow down near the goal so the drawer does not slide on past it.
        speed = float(np.clip(abs(goal - art.qpos) / 0.03, 0.15, 0.6))
        yield agent.command(target, speed=speed)
    yield from move(agent, agent.scene.eef_pos, tol=0.002, steps=3)  # let the drawer stop with the hand
    yield from actuate(agent, OPEN)
    yield from move(agent, agent.scene.eef_pos + 0.08 * direction, tol=0.02, steps=20)
    return agent.scene.articulation(region).holds("open")


def push_closed(agent: Agent, region: str) -> Program:
    """Close a drawer by pushing its front (through the handle) with the closed fingers."""
    art = agent.scene.articulation(region)
    direction = _opening_direction(art)
    yaw = wrap_half_turn(math.atan2(direction[1], direction[0]) + math.pi / 2, closing_yaw(agent.scene.eef_mat))
    rot = top_down(yaw)
    contact = art.handle + direction * (hand.FINGER_DEPTH + 0.02)
    contact[2] = art.handle[2] + hand.TIP
    yield from actuate(agent, CLOSE, max_steps=8)
    yield from reorient(agent, rot)
    above = contact + np.array([0.0, 0.0, 0.05])
    path = flight_path(agent.scene, agent.scene.eef_pos, above, hang=hand.TIP, reach=HAND_REACH)
    yield from travel(agent, contact, path=path, rot=rot, grip=CLOSE, tol=0.01)
    for _ in range(60):
        art = agent.scene.articulation(region)
        if art.holds("close"):
            break
        target = art.handle.copy() - direction * 0.05
        target[2] = contact[2]
        yield agent.command(target, speed=0.5)
    yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, RETREAT]), tol=0.02, steps=20)
    return agent.scene.articulation(region).holds("close")


def turn(agent: Agent, fixture: str, state: str) -> Program:
    """Turn a knob (a hinge about a vertical axis) into the qpos interval of `state`."""
    art = agent.scene.articulation(fixture)
    top = art.bbox[5]
    grasp_point = np.array([art.anchor[0], art.anchor[1], top - 0.015])
    knob = art.boxes.aabb()
    grip_slab = knob[knob[:, 5] > top - 0.02]
    extent = grip_slab[:, 3:5].max(axis=0) - grip_slab[:, :2].min(axis=0)
    # Close across the knob's narrow side.
    yaw = 0.0 if extent[0] < extent[1] else math.pi / 2
    yaw = wrap_half_turn(yaw, closing_yaw(agent.scene.eef_mat))
    above = grasp_point + np.array([0.0, 0.0, APPROACH])
    yield from reorient(agent, top_down(yaw))
    path = flight_path(agent.scene, agent.scene.eef_pos, above, hang=hand.TIP, reach=HAND_REACH)
    yield from travel(agent, above, path=path, rot=top_down(yaw), grip=OPEN, tol=0.01)
    yield from move(agent, grasp_point, tol=0.004, steps=40, speed=0.4)
    yield from actuate(agent, CLOSE)
    goal = art.target(state)
    spin = float(np.sign(art.axis[2]))
    for _ in range(40):
        art = agent.scene.articulation(fixture)
        if art.holds(state):
            break
        step = float(np.clip(goal - art.qpos, -0.4, 0.4)) * spin
        rot = rotation_about(np.array([0.0, 0.0, 1.0]), step) @ agent.scene.eef_mat
        yield agent.command(grasp_point, rot=rot)
    yield from actuate(agent, OPEN)
    yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, RETREAT]), tol=0.02, steps=20)
    return agent.scene.articulation(fixture).holds(state)


def push_to(agent: Agent, obj: str, spot: Spot, *, tolerance: float = 0.01) -> Program:
    """Slide `obj` over the table until its origin is within `tolerance` of `spot`, pushing with the fingertips."""
    scene = agent.scene
    for _ in range(4):
        scene = agent.scene
        to_go = spot.xy - scene.pos(obj)[:2]
        if np.linalg.norm(to_go) < tolerance:
            return True
        direction = to_go / np.linalg.norm(to_go)
        box = scene.bbox(obj)
        radius = float(np.max(np.abs(np.concatenate([box[:2], box[3:5]]) - np.tile(scene.pos(obj)[:2], 2))))
        yaw = wrap_half_turn(math.atan2(direction[1], direction[0]) + math.pi / 2, closing_yaw(scene.eef_mat))
        z = box[2] + hand.TIP + 0.006
        start = np.array([*(scene.pos(obj)[:2] - direction * (radius + hand.FINGER_DEPTH + 0.02)), z])
        yield from reorient(agent, top_down(yaw))
        scene = agent.scene
        path = flight_path(scene, scene.eef_pos, start + np.array([0.0, 0.0, 0.05]), hang=hand.TIP, reach=HAND_REACH)
        yield from travel(agent, start, path=path, rot=top_down(yaw), grip=CLOSE, tol=0.008)
        for _ in range(80):
            scene = agent.scene
            to_go = spot.xy - scene.pos(obj)[:2]
            if np.linalg.norm(to_go) < tolerance:
                break
            # Push through the object's centre toward the spot; drift sideways re-aims the next pass.
            lateral = np.cross(np.r_[direction, 0.0], np.r_[scene.pos(obj)[:2] - scene.eef_pos[:2], 0.0])[2]
            if abs(lateral) > 0.03:
                break
            target = np.array([*(scene.eef_pos[:2] + direction * min(0.03, np.linalg.norm(to_go) + 0.005)), z])
            yield agent.command(target, speed=0.5)
        yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, 0.06]), tol=0.02, steps=15)
    return bool(np.linalg.norm(spot.xy - agent.scene.pos(obj)[:2]) < tolerance)


def close_door(agent: Agent, fixture: str) -> Program:
    """Swing a hinged door shut by pushing its free edge around the hinge with the closed fingers."""
    art = agent.scene.articulation(fixture)
    goal = art.target("close")
    yield from actuate(agent, CLOSE, max_steps=8)
    for _ in range(120):
        art = agent.scene.articulation(fixture)
        if art.holds("close"):
            break
        parts = art.boxes.aabb()
        centres = (parts[:, :3] + parts[:, 3:]) / 2.0
        arm = centres[:, :2] - art.anchor[:2]
        far = centres[np.argmax(np.linalg.norm(arm, axis=1))]
        radius = np.r_[far[:2] - art.anchor[:2], 0.0]
        sense = np.sign(goal - art.qpos) * np.sign(art.axis[2])
        tangent = np.cross(np.array([0.0, 0.0, sense]), radius)
        tangent /= np.linalg.norm(tangent)
        z = (parts[:, 2].min() + parts[:, 5].max()) / 2.0
        behind = np.array([*(far[:2] - tangent[:2] * 0.04), z])
        if np.dot(agent.scene.eef_pos[:2] - far[:2], tangent[:2]) > -0.01:
            # Not yet behind the door's edge: go around it from above.
            over = np.array([*behind[:2], max(parts[:, 5].max() + 0.05, agent.scene.eef_pos[2])])
            path = np.array([[*agent.scene.eef_pos[:2], over[2]], over])
            yield from travel(agent, behind, path=path, rot=agent.rot, grip=CLOSE, tol=PASS_TOLERANCE)
            continue
        yield agent.command(np.array([*(far[:2] + tangent[:2] * 0.03), z]), speed=0.6)
    yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, RETREAT]), tol=0.02, steps=20)
    return agent.scene.articulation(fixture).holds("close")
