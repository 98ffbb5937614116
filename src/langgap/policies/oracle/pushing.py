"""Sliding an object over the table with the closed fingers (for what no grasp fits, e.g. a plate):
dragged by the fingers pressed inside it when it has a hollow, else pushed from behind."""

from __future__ import annotations

import math

import numpy as np

from langgap.policies.oracle import hand, hooking
from langgap.policies.oracle.control import CLOSE
from langgap.policies.oracle.geometry import (
    Boxes,
    boxes_hit,
    depth,
    hand_yaw,
    leaning,
    top_down,
    wrap_half_turn,
)
from langgap.policies.oracle.motion import Agent, Program, actuate, move, reorient, travel
from langgap.policies.oracle.placement import Spot, flight_path, footprint_at
from langgap.policies.oracle.scene import Scene

PUSH_LEANS = (0.0, 0.35, 0.6)  # radians the fingers may lean back when pushing an object
PUSH_TURNS = (0.0, math.pi / 4, -math.pi / 4)
PUSH_TOLERANCE = 0.004
LOOSE_ALLOWANCE = 0.018  # how far the hand may push into another loose object on its way
FINAL_STROKES = 3  # strokes toward the goal (a stop on the way gets one)
PRESS = 0.012  # metres below the fingers' height the push is aimed
PUSH_GAP = 0.005  # between the fingers and the object before a stroke
PUSH_HEIGHT = 0.004  # of the hand's lowest point above the table
PUSH_DETOURS = (0.08, 0.14)  # how far a first stroke may take an object before it is pushed toward its goal
STROKE_COST = 0.05  # metres of detour worth saving a stroke
SLIDE_DRAGS = 3  # pressed drags toward the spot, each from where the last one left the object


def _push_pose(
    scene: Scene, obj: str, origin: np.ndarray, direction: np.ndarray, distance: float
) -> tuple[np.ndarray, np.ndarray] | None:
    """How to push `obj`, with its origin at `origin`, along `direction`: (grip-site start, rot), or None.

    The closed fingers stand just behind the object's trailing side, tips just above the table,
    closing across the push. When the upright hand would hit something (a cabinet's handles behind
    the object), the fingers lean back so the palm rides forward over the object.
    """
    target = footprint_at(scene, obj, origin, scene.bbox(obj)[2])
    table = float(scene.bbox(obj)[2])
    across = math.atan2(direction[1], direction[0]) + math.pi / 2
    fixed = scene.obstacles(exclude=(obj,), fixtures_only=True)
    loose = scene.loose_boxes(exclude=(obj,))
    push = np.array([*direction, 0.0])
    for lean in PUSH_LEANS:
        for turn in PUSH_TURNS:  # a turned hand reaches less far sideways
            yaw = wrap_half_turn(across + turn, hand_yaw(scene.eef_mat))
            rot = leaning(top_down(yaw), -push, lean) if lean else top_down(yaw)
            start = _behind(target, table, origin, direction, rot)
            poses = [start + np.array([0.0, 0.0, lift]) for lift in (0.0, 0.05, 0.1)]
            before = Boxes.concat([hands_at(rot, p) for p in poses])
            during = Boxes.concat([hands_at(rot, start + push * distance * t) for t in (0.5, 1.0)])
            hands = Boxes.concat([before, during])
            if (
                not boxes_hit(hands, fixed, PUSH_TOLERANCE)
                and depth(hands, loose) < LOOSE_ALLOWANCE
                and not boxes_hit(before, target, PUSH_TOLERANCE)
            ):
                return start, rot
    return None


def hands_at(rot: np.ndarray, point: np.ndarray) -> Boxes:
    """The closed hand with its grip site at `point`."""
    return Boxes.from_local(hand.local_boxes(0.0), rot, point)


def _behind(target: Boxes, table: float, origin: np.ndarray, direction: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """The grip site that puts the hand's lowest point just above the table, `PUSH_GAP` behind `target`."""
    lowest = float(hands_at(rot, np.zeros(3)).aabb()[:, 2].min())
    z = table + PUSH_HEIGHT - lowest
    near, far = 0.0, 0.3  # distances back from the origin: touching at `near`, clear at `far`
    for _ in range(16):
        middle = (near + far) / 2.0
        point = np.array([*(origin - direction * middle), z])
        if depth(hands_at(rot, point), target) > -PUSH_GAP:
            near = middle
        else:
            far = middle
    return np.array([*(origin - direction * far), z])


def _push_plan(scene: Scene, obj: str, goal: np.ndarray) -> list[np.ndarray]:
    """Stops (ending with `goal`) for pushing `obj` there in at most three straight strokes.

    Each stroke needs a clear pushing pose and a path for the object clear of the fixtures; the
    shortest plan wins (a direct push when it is clear).
    """
    here = scene.pos(obj)[:2]
    fixed = scene.obstacles(exclude=(obj,), fixtures_only=True)
    table = float(scene.bbox(obj)[2]) + 0.003
    cache: dict[tuple, float] = {}

    def cost(a: np.ndarray, b: np.ndarray) -> float:
        """The stroke's length, or infinity if it cannot be made."""
        key = (*np.round(a, 4), *np.round(b, 4))
        if key not in cache:
            step = b - a
            length = float(np.linalg.norm(step))
            if length < 1e-3:
                cache[key] = 0.0
            elif _push_pose(scene, obj, a, step / length, length) is None:
                cache[key] = np.inf
            else:
                swept = [footprint_at(scene, obj, a + t * step, table) for t in (0.25, 0.5, 0.75, 1.0)]
                blocked = any(boxes_hit(boxes, fixed, PUSH_TOLERANCE) for boxes in swept)
                cache[key] = np.inf if blocked else length
        return cache[key]

    stops = [here + d * np.array([math.cos(a), math.sin(a)]) for d in PUSH_DETOURS for a in np.arange(8) * math.pi / 4]
    plans = [[goal]]
    for stop in stops + [np.array([goal[0], here[1]]), np.array([here[0], goal[1]])]:
        plans.append([stop, goal])
        plans += [[stop, np.array([goal[0], stop[1]]), goal], [stop, np.array([stop[0], goal[1]]), goal]]
    best, best_cost = [goal], np.inf
    for plan in plans:
        points = [here, *plan]
        lower = sum(float(np.linalg.norm(b - a)) for a, b in zip(points, points[1:], strict=False))
        if lower + STROKE_COST * len(plan) >= best_cost:
            continue
        total = sum(cost(a, b) for a, b in zip(points, points[1:], strict=False)) + STROKE_COST * len(plan)
        if total < best_cost:
            best, best_cost = plan, total
    return best


def slide_to(agent: Agent, obj: str, spot: Spot, *, tolerance: float = 0.01) -> Program:
    """Slide `obj` over the table until its origin is within `tolerance` of `spot`: pressed drags
    (`hooking`) while a hook fits it, then pushes from behind (`push_to`)."""
    for _ in range(SLIDE_DRAGS):
        if _arrived(agent.scene, obj, spot, tolerance):
            return True
        hook = hooking.plan_hook(agent.scene, obj, spot.xy - agent.scene.pos(obj)[:2], pressed=True)
        if hook is None:
            return (yield from push_to(agent, obj, spot, tolerance=tolerance))
        yield from hooking.drag(agent, hook)
    return _arrived(agent.scene, obj, spot, tolerance)


def _arrived(scene: Scene, obj: str, spot: Spot, tolerance: float) -> bool:
    return bool(np.linalg.norm(spot.xy - scene.pos(obj)[:2]) < tolerance)


def push_to(agent: Agent, obj: str, spot: Spot, *, tolerance: float = 0.01) -> Program:
    """Slide `obj` over the table until its origin is within `tolerance` of `spot`, pushing with the fingers."""
    stops = _push_plan(agent.scene, obj, spot.xy)
    for stop in stops:
        final = stop is stops[-1]
        # A stop on the way needs one stroke toward it; only the goal is worth correcting strokes.
        for _ in range(FINAL_STROKES if final else 1):
            scene = agent.scene
            to_go = stop - scene.pos(obj)[:2]
            if np.linalg.norm(to_go) < (tolerance if final else 0.02):
                break
            direction = to_go / np.linalg.norm(to_go)
            pose = _push_pose(scene, obj, scene.pos(obj)[:2], direction, float(np.linalg.norm(to_go)))
            start, rot = pose if pose is not None else _push_pose_upright(scene, obj, direction)
            yield from actuate(agent, CLOSE, max_steps=8)
            yield from reorient(agent, rot, toward=start)
            scene = agent.scene
            path = flight_path(scene, scene.eef_pos, start + np.array([0.0, 0.0, 0.1]), hang=hand.TIP, reach=hand.REACH)
            yield from travel(agent, start, path=path, rot=rot, grip=CLOSE, tol=0.008)
            for _ in range(80):
                scene = agent.scene
                to_go = stop - scene.pos(obj)[:2]
                if np.linalg.norm(to_go) < tolerance:
                    break
                # Push through the object's centre toward the stop; drift sideways re-aims the next stroke.
                lateral = np.cross(np.r_[direction, 0.0], np.r_[scene.pos(obj)[:2] - scene.eef_pos[:2], 0.0])[2]
                if abs(lateral) > 0.03 or np.dot(to_go, direction) < 0:
                    break
                step = direction * min(0.03, np.linalg.norm(to_go) + 0.005)
                # Aimed a little into the table: the hand presses down instead of riding up over the object.
                yield agent.command(np.array([*(scene.eef_pos[:2] + step), start[2] - PRESS]), speed=0.5)
            yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, 0.06]), tol=0.02, steps=15)
    return _arrived(agent.scene, obj, spot, tolerance)


def _push_pose_upright(scene: Scene, obj: str, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The upright pushing pose, used when no pose is clear (the best that can be done)."""
    yaw = wrap_half_turn(math.atan2(direction[1], direction[0]) + math.pi / 2, hand_yaw(scene.eef_mat))
    origin = scene.pos(obj)[:2]
    table = float(scene.bbox(obj)[2])
    return _behind(scene.boxes(obj), table, origin, direction, top_down(yaw)), top_down(yaw)
