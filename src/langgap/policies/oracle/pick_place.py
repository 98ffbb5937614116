"""Picking an object up and putting it down on a spot.

Each skill is a program (see `motion`) that reads the scene afresh at every step, so it follows
objects that move, and returns whether it believes it succeeded; the planner verifies and retries.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.carry import release_route
from langgap.policies.oracle.control import CLOSE, OPEN
from langgap.policies.oracle.geometry import bounds_corners_xy, bounds_xy
from langgap.policies.oracle.grasps import APPROACHES, plan_grasp
from langgap.policies.oracle.motion import (
    PASS_TOLERANCE,
    Agent,
    Program,
    actuate,
    back_off,
    move,
    reorient,
    stalled,
    travel,
)
from langgap.policies.oracle.placement import HAND_HALF_WIDTH, LOAD_MARGIN, Spot, flight_path, footprint_at

LIFT = 0.08  # lift after grasping before flying
GRASP_TOLERANCE = 0.005
LIFTED = 0.02  # an object that rose this much with the hand is held
PLACE_CLEARANCE = 0.03  # released objects are lowered from this high above the support
PLACE_SPEED = 0.35  # touching down
SLOW_ZONE = 0.04  # above the release point the descent slows from the carrying speed to PLACE_SPEED
CARRY_SPEED = 1.0  # loads are carried at full speed (lowered gently: PLACE_SPEED)
SAG = 0.3  # allowance for a pinched load's far side drooping, per metre of its reach beyond the fingers
PICK_ATTEMPTS = 3
SPOT_TRIES = 6  # spots tried for a grasp whose hand also fits where the object goes
RELEASE_STEPS = 6  # enough for the fingers to let go; they keep opening while the hand backs off
RELEASE_GAP = 0.005  # the load is lowered to this far above its support, then until it touches
PLACE_STALL = 5  # steps without descending after which the load is released where it is


def _hang(agent: Agent, obj: str) -> float:
    """How far the held object reaches below the grip site."""
    return float(agent.scene.eef_pos[2] - agent.scene.bbox(obj)[2])


def _descent_speed(height: float) -> float:
    """How fast to lower a load `height` above its release point: fast from high up, gently near it."""
    return float(np.clip(height / SLOW_ZONE * CARRY_SPEED, PLACE_SPEED, CARRY_SPEED))


def pick(agent: Agent, obj: str, spots: Sequence[Spot] = ()) -> Program:
    """Grasp `obj` from above and lift it; returns the spot of `spots` (where it may go) the grasp
    suits, the first one if none is checked, or None if the object could not be picked up.

    The spots are tried in order until a grasp is found whose hand also fits at the spot.
    """
    for _ in range(PICK_ATTEMPTS):
        scene = agent.scene
        grasp, spot = None, spots[0] if spots else None
        place_obstacles = scene.obstacles(exclude=(obj,)) if spots else None
        for candidate in list(spots[:SPOT_TRIES]) or [None]:
            shift = None
            if candidate is not None:
                shift = footprint_at(scene, obj, candidate.xy, candidate.support).centre[0] - scene.boxes(obj).centre[0]
            found = plan_grasp(scene, obj, place_shift=shift, place_obstacles=place_obstacles, approach=APPROACHES[0])
            if found is not None and (grasp is None or found.cost < grasp.cost):
                grasp, spot = found, candidate
            if grasp is not None and grasp.placeable:
                break
        if grasp is None:
            return None
        first = grasp.entry[0]
        yield from reorient(agent, grasp.rot, toward=first)
        path = flight_path(agent.scene, agent.scene.eef_pos, first, hang=hand.TIP, reach=hand.REACH)
        yield from travel(agent, first, path=path, rot=grasp.rot, grip=OPEN, tol=0.01)
        for waypoint in grasp.entry[1:]:
            yield from move(agent, waypoint, tol=0.01, steps=30, speed=0.6)
        start_z = agent.scene.pos(obj)[2]
        yield from move(agent, grasp.point, tol=GRASP_TOLERANCE, steps=40, speed=0.8)
        yield from actuate(agent, CLOSE)
        lift_to = agent.scene.eef_pos + np.array([0.0, 0.0, LIFT])
        # Not stopping up there: the flight to the place continues from wherever the lift ends.
        yield from move(agent, lift_to, tol=PASS_TOLERANCE, steps=30, speed=0.6, through=True)
        if agent.scene.touches_gripper(obj) and agent.scene.pos(obj)[2] - start_z > LIFTED:
            return spot if spot is not None else True
        yield from actuate(agent, OPEN)
        yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, 0.05]), tol=0.015, steps=15)
    return None


def place(agent: Agent, obj: str, spot: Spot) -> Program:
    """Carry the held `obj` over `spot`, lower it until it touches down, release it and back off."""
    scene = agent.scene
    offset = scene.eef_pos - scene.pos(obj)
    goal_xy = spot.xy + offset[:2]
    box = scene.bbox(obj)
    span = float(np.max(np.linalg.norm(bounds_corners_xy(box) - scene.eef_pos[:2], axis=1)))
    # A load pinched off-centre pivots in the fingers: its far side may sag this much lower.
    hang = _hang(agent, obj) + SAG * max(0.0, span - hand.PAD_GAP_OPEN)
    # What the hand carries, around the grip site: the load as it hangs there and the fingers.
    carried = bounds_xy(box, scene.eef_pos)
    extent = np.concatenate([np.minimum(carried[:2], -HAND_HALF_WIDTH), np.maximum(carried[2:], HAND_HALF_WIDTH)])
    release = np.array([*goal_xy, spot.support + _hang(agent, obj) + RELEASE_GAP])
    route = release_route(scene, obj, release, scene.eef_mat.copy(), PLACE_CLEARANCE + hang - _hang(agent, obj))
    above = route[0]
    above_z = above[2]
    footprint = bounds_xy(box) + np.array([-0.01, -0.01, 0.01, 0.01])
    path = flight_path(
        scene, scene.eef_pos, above, exclude=(obj,), hang=hang, reach=LOAD_MARGIN, extent=extent, footprint=footprint
    )
    yield from travel(agent, above, path=path, tol=0.012, speed=CARRY_SPEED)
    for waypoint in route[1:-1]:
        yield from move(agent, waypoint, tol=0.01, steps=30, speed=0.5)
    if len(route) > 2:
        yield from move(agent, route[-1], tol=0.008, steps=30, speed=0.4)
    floor = release[2] - RELEASE_GAP - 0.005
    heights: list[float] = []
    for _ in range(60):
        scene = agent.scene
        if not scene.touches_gripper(obj):
            break  # dropped on the way: let it be
        if scene.eef_pos[2] <= floor + 0.002 or (scene.touches_other(obj) and scene.eef_pos[2] < above_z - 0.01):
            break
        heights.append(float(scene.eef_pos[2]))
        if stalled(heights, PLACE_STALL, 0.002):
            break  # the hand rests on something (a basket's rim): release from here
        correction = spot.xy - scene.pos(obj)[:2]
        target = np.array([*(scene.eef_pos[:2] + correction), floor - 0.01])
        yield agent.command(target, speed=_descent_speed(scene.eef_pos[2] - release[2]))
    yield from actuate(agent, OPEN, min_steps=RELEASE_STEPS, max_steps=RELEASE_STEPS)
    if len(route) > 2:  # came in from the side: leave the same way
        back = route[-2] + np.array([0.0, 0.0, agent.scene.eef_pos[2] - route[-1][2]])
        yield from move(agent, back, tol=0.015, steps=25, speed=0.6)
    yield from back_off(agent)
    return True
