"""Skills: pick, place, pull or push a drawer, turn a knob, push an object, close a door.

Each skill is a program (see `motion`) that reads the scene afresh at every step, so it follows
objects that move, and returns whether it believes it succeeded; the planner verifies and retries.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.carry import release_route
from langgap.policies.oracle.control import CLOSE, OPEN
from langgap.policies.oracle.geometry import (
    Boxes,
    boxes_hit,
    closing_yaw,
    depth,
    rotation_about,
    top_down,
    wrap_half_turn,
)
from langgap.policies.oracle.grasps import PENETRATION_TOLERANCE, REACH_WEIGHT, hand_hits, plan_grasp
from langgap.policies.oracle.motion import Agent, Program, actuate, move, reorient, travel
from langgap.policies.oracle.placement import Spot, flight_path, footprint_at
from langgap.policies.oracle.scene import Scene

APPROACH = 0.05  # pre-grasp height above the grasp point
LIFT = 0.08  # lift after grasping before flying
GRASP_TOLERANCE = 0.005
LIFTED = 0.02  # an object that rose this much with the hand is held
RETREAT = 0.08
PLACE_CLEARANCE = 0.03  # released objects are lowered from this high above the support
PLACE_SPEED = 0.35
CARRY_SPEED = 0.8  # a load held by its rim swings loose when flung about
SAG = 0.3  # allowance for a pinched load's far side drooping, per metre of its reach beyond the fingers
PICK_ATTEMPTS = 3
SPOT_TRIES = 6  # spots tried for a grasp whose hand also fits where the object goes
RELEASE_STEPS = 6  # enough for the fingers to let go; they keep opening while the hand backs off
RELEASE_GAP = 0.005  # the load is lowered to this far above its support, then until it touches
PLACE_STALL = 5  # steps without descending after which the load is released where it is
HAND_REACH = 0.07  # how far the open fingers reach sideways from the grip site
PUSH_BESIDE = 0.03  # a drawer is pushed this far beside its handle
HANDLE_HALF_HEIGHT = 0.008
PUSH_LEAN = 0.6  # radians
HANDLE_APPROACH = 0.07  # the hand slides this far onto a drawer's handle
WRIST_OFFSET = 0.15  # the wrist is this far behind the grip site
SIDE_ANGLES = (0.0, math.radians(15), math.radians(30))
LOOSE_WEIGHT = 300.0  # cost per metre the hand would push into a loose object
LOOSE_ALLOWANCE = 0.006
WRIST_REACH = 0.6  # horizontal distance from the base beyond which the wrist nears the arm's reach
PUSH_LEANS = (0.0, 0.35, 0.6)  # radians the fingers may lean back when pushing an object
PUSH_TOLERANCE = 0.004
PUSH_TURNS = (0.0, math.pi / 4, -math.pi / 4)
PUSH_DETOURS = (0.08, 0.14)  # how far a first stroke may take an object before it is pushed toward its goal
DOOR_PUSH_AT = 0.75  # fraction of a door's width from its hinge where it is pushed


def _hang(agent: Agent, obj: str) -> float:
    """How far the held object reaches below the grip site."""
    return float(agent.scene.eef_pos[2] - agent.scene.bbox(obj)[2])


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
            found = plan_grasp(scene, obj, place_shift=shift, place_obstacles=place_obstacles, approach=APPROACH)
            if found is not None and (grasp is None or found.cost < grasp.cost):
                grasp, spot = found, candidate
            if grasp is not None and grasp.placeable:
                break
        if grasp is None:
            return None
        first = grasp.entry[0]
        yield from reorient(agent, grasp.rot)
        path = flight_path(agent.scene, agent.scene.eef_pos, first, hang=hand.TIP, reach=HAND_REACH)
        yield from travel(agent, first, path=path, rot=grasp.rot, grip=OPEN, tol=0.01)
        for waypoint in grasp.entry[1:]:
            yield from move(agent, waypoint, tol=0.01, steps=30, speed=0.6)
        start_z = agent.scene.pos(obj)[2]
        yield from move(agent, grasp.point, tol=GRASP_TOLERANCE, steps=40, speed=0.8)
        yield from actuate(agent, CLOSE)
        lift_to = agent.scene.eef_pos + np.array([0.0, 0.0, LIFT])
        yield from move(agent, lift_to, tol=0.015, steps=30, speed=0.6)
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
    corners = np.array([[x, y] for x in (box[0], box[3]) for y in (box[1], box[4])])
    reach = float(np.max(np.linalg.norm(corners - scene.eef_pos[:2], axis=1)))
    # A load pinched off-centre pivots in the fingers: its far side may sag this much lower.
    hang = _hang(agent, obj) + SAG * max(0.0, reach - hand.PAD_GAP_OPEN)
    reach += 0.015
    release = np.array([*goal_xy, spot.support + _hang(agent, obj) + RELEASE_GAP])
    route = release_route(scene, obj, release, scene.eef_mat.copy(), PLACE_CLEARANCE + hang - _hang(agent, obj))
    above = route[0]
    above_z = above[2]
    footprint = scene.bbox(obj)[[0, 1, 3, 4]] + np.array([-0.01, -0.01, 0.01, 0.01])
    path = flight_path(scene, scene.eef_pos, above, exclude=(obj,), hang=hang, reach=reach, footprint=footprint)
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
        if len(heights) > PLACE_STALL and heights[-PLACE_STALL - 1] - heights[-1] < 0.002:
            break  # the hand rests on something (a basket's rim): release from here
        correction = spot.xy - scene.pos(obj)[:2]
        target = np.array([*(scene.eef_pos[:2] + correction), floor - 0.01])
        yield agent.command(target, speed=PLACE_SPEED)
    yield from actuate(agent, OPEN, min_steps=RELEASE_STEPS, max_steps=RELEASE_STEPS)
    if len(route) > 2:  # came in from the side: leave the same way
        back = route[-2] + np.array([0.0, 0.0, agent.scene.eef_pos[2] - route[-1][2]])
        yield from move(agent, back, tol=0.015, steps=25, speed=0.6)
    yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, RETREAT]), tol=0.02, steps=20)
    return True


def _opening_direction(art) -> np.ndarray:
    """Horizontal unit vector a slide joint's part travels along when it opens."""
    sign = np.sign(art.intervals["open"].mean() - art.intervals["close"].mean())
    direction = sign * art.axis * np.sign(art.limits[1] - art.limits[0])
    direction = np.array([direction[0], direction[1], 0.0])
    return direction / np.linalg.norm(direction)


def _pointing(approach: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """A gripper frame pointing along `approach` (horizontal) with its fingers closing vertically.

    Of the two such frames (a parallel gripper is symmetric) the one nearer `reference` is used,
    which keeps the wrist within its joint limits when turning from a top-down pose.
    """
    candidates = []
    for up in (1.0, -1.0):
        x = np.array([0.0, 0.0, up])
        candidates.append(np.stack([x, np.cross(approach, x), approach], axis=1))
    return min(candidates, key=lambda rot: np.linalg.norm(rot - reference))


def _handle_grasp(agent: Agent, art, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How to take a drawer's handle bar with the fingers closing across it vertically: (rot, grasp, approach).

    From the front, or along the bar from either end (the hand then stays beside the drawer, and
    the wrist nearer the robot when the cabinet faces sideways). The clear option that least
    stretches the arm wins.
    """
    _, axis, half_length = _front(art, direction)
    options = [(-direction, art.handle + hand.PAD_CENTRE * direction)]
    for side in (1.0, -1.0):
        along = side * axis  # the fingers slide onto the bar from its end
        grasp = art.handle - along * (half_length + hand.PAD_CENTRE - hand.PAD_HALF_HEIGHT)
        for angle in SIDE_ANGLES:  # turned away from the drawer's face, to keep the hand clear of the cabinet
            options.append((np.cos(angle) * along - np.sin(angle) * direction, grasp))
    fixed = agent.scene.obstacles(fixtures_only=True)
    loose = Boxes.concat([agent.scene.boxes(e) for e in agent.scene.entities if agent.scene.movable(e)])
    local = np.concatenate([hand.finger_boxes(hand.PAD_GAP_OPEN), hand.palm_boxes()])
    best, best_cost = None, np.inf
    for approach, grasp in options:
        rot = _pointing(approach, agent.scene.eef_mat)
        ready = grasp - HANDLE_APPROACH * approach
        # The hand at the grasp, where it starts sliding onto the bar, and on its way down there.
        poses = [grasp, ready] + [ready + np.array([0.0, 0.0, lift]) for lift in (0.05, 0.1, 0.15)]
        hands = Boxes.concat([Boxes.from_local(local, rot, pose) for pose in poses])
        cost = REACH_WEIGHT * max(0.0, agent.scene.reach(grasp - approach * WRIST_OFFSET) - WRIST_REACH)
        cost += 10.0 * boxes_hit(hands, fixed, PENETRATION_TOLERANCE)
        # Brushing a loose object is acceptable; ramming one (a bottle beside the cabinet) is not.
        cost += LOOSE_WEIGHT * max(0.0, depth(hands, loose) - LOOSE_ALLOWANCE)
        if cost < best_cost:
            best, best_cost = (rot, grasp, approach), cost
    return best


def pull_open(agent: Agent, region: str) -> Program:
    """Open a drawer: take its handle bar with the fingers closing vertically, pull it out."""
    art = agent.scene.articulation(region)
    direction = _opening_direction(art)
    rot, grasp, approach = _handle_grasp(agent, art, direction)
    ready = grasp - HANDLE_APPROACH * approach
    yield from reorient(agent, rot)
    path = flight_path(agent.scene, agent.scene.eef_pos, ready, hang=hand.PALM_HALF_LENGTH, reach=HAND_REACH)
    yield from travel(agent, ready, path=path, rot=rot, grip=OPEN, tol=0.01)
    yield from move(agent, grasp, tol=0.006, steps=40, speed=0.5)
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


def _front(art, direction: np.ndarray) -> tuple[float, np.ndarray, float]:
    """A drawer's front: the face's reach along `direction`, the handle bar's axis and its half-length."""
    boxes = art.boxes
    local = np.abs(np.einsum("nji,j->ni", boxes.rot, direction))
    reach = boxes.centre @ direction + np.sum(local * boxes.half, axis=1)
    handle = reach >= reach.max() - 0.01
    face = float(reach[~handle].max()) if (~handle).any() else float(reach.max())
    axis = np.cross([0.0, 0.0, 1.0], direction)
    along = np.abs(np.einsum("nji,j->ni", boxes.rot, axis))
    extent = boxes.centre[handle] @ axis
    half = np.sum(along[handle] * boxes.half[handle], axis=1)
    centre = art.handle @ axis
    half_length = float(max(np.max(extent + half) - centre, centre - np.min(extent - half)))
    return face, axis, half_length


def _leaning(rot: np.ndarray, toward: np.ndarray, angle: float) -> np.ndarray:
    """`rot` turned about its closing axis so that its fingers point `angle` radians toward `toward`."""
    axis = rot[:, 0]
    turned = rotation_about(axis, angle) @ rot
    return turned if np.dot(turned[:, 2], toward) > 0 else rotation_about(axis, -angle) @ rot


def push_closed(agent: Agent, region: str) -> Program:
    """Close a drawer by pushing its front, beside the handle, with the closed fingers."""
    art = agent.scene.articulation(region)
    direction = _opening_direction(art)
    face, axis, half_length = _front(art, direction)
    yaw = wrap_half_turn(math.atan2(axis[1], axis[0]), closing_yaw(agent.scene.eef_mat))
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
    rot = _leaning(rot, -direction, PUSH_LEAN)
    yield from actuate(agent, CLOSE, max_steps=8)
    yield from reorient(agent, rot)
    above = contact + np.array([0.0, 0.0, 0.05])
    path = flight_path(agent.scene, agent.scene.eef_pos, above, hang=hand.TIP, reach=HAND_REACH)
    yield from travel(agent, contact, path=path, rot=rot, grip=CLOSE, tol=0.01)
    for _ in range(60):
        art = agent.scene.articulation(region)
        if art.reached("close"):
            break
        target = agent.scene.eef_pos - direction * 0.03
        target[2] = contact[2]
        yield agent.command(target, speed=0.6)
    yield from move(agent, agent.scene.eef_pos + direction * 0.03 + np.array([0.0, 0.0, RETREAT]), tol=0.02, steps=20)
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
        if art.reached(state):
            break
        step = float(np.clip(goal - art.qpos, -0.4, 0.4)) * spin
        rot = rotation_about(np.array([0.0, 0.0, 1.0]), step) @ agent.scene.eef_mat
        yield agent.command(grasp_point, rot=rot)
    yield from actuate(agent, OPEN)
    yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, RETREAT]), tol=0.02, steps=20)
    return agent.scene.articulation(fixture).holds(state)


def _push_pose(
    scene: Scene, obj: str, origin: np.ndarray, direction: np.ndarray, distance: float
) -> tuple[np.ndarray, np.ndarray] | None:
    """How to push `obj`, with its origin at `origin`, along `direction`: (grip-site start, rot), or None.

    The closed fingers touch the object's trailing side, tips just above the table, closing across
    the push. When the upright hand would hit something (a cabinet's handles behind the object),
    the fingers lean back so the palm rides forward over the object.
    """
    shift = np.array([*(origin - scene.pos(obj)[:2]), 0.0])
    box = scene.bbox(obj) + np.tile(shift, 2)
    corners = np.array([[x, y] for x in (box[0], box[3]) for y in (box[1], box[4])]) - origin
    behind = float(np.max(-(corners @ direction)))
    start = np.array([*(origin - direction * (behind + hand.FINGER_DEPTH + 0.008)), box[2] + hand.TIP + 0.006])
    across = math.atan2(direction[1], direction[0]) + math.pi / 2
    fixed = scene.obstacles(exclude=(obj,), fixtures_only=True)
    loose = Boxes.concat([scene.boxes(e) for e in scene.entities if e != obj and scene.movable(e)])
    local = np.concatenate([hand.finger_boxes(0.0), hand.palm_boxes()])
    push = np.array([*direction, 0.0])
    for lean in PUSH_LEANS:
        for turn in PUSH_TURNS:  # a turned hand reaches less far sideways
            yaw = wrap_half_turn(across + turn, closing_yaw(scene.eef_mat))
            rot = _leaning(top_down(yaw), -push, lean) if lean else top_down(yaw)
            poses = [start + np.array([0.0, 0.0, lift]) for lift in (0.0, 0.05, 0.1)]
            poses += [start + push * distance * t for t in (0.5, 1.0)]
            hands = Boxes.concat([Boxes.from_local(local, rot, p) for p in poses])
            if not boxes_hit(hands, fixed, PUSH_TOLERANCE) and depth(hands, loose) < LOOSE_ALLOWANCE * 3:
                return start, rot
    return None


def _push_plan(scene: Scene, obj: str, goal: np.ndarray) -> list[np.ndarray]:
    """Stops (ending with `goal`) for pushing `obj` there in at most three straight strokes.

    Each stroke needs a clear pushing pose and a clear path for the object past the fixtures;
    the shortest such plan wins (a direct push when it is clear).
    """
    here = scene.pos(obj)[:2]
    fixed = scene.obstacles(exclude=(obj,), fixtures_only=True)
    cache: dict[tuple, bool] = {}

    def clear(a: np.ndarray, b: np.ndarray) -> bool:
        key = (*np.round(a, 4), *np.round(b, 4))
        if key not in cache:
            step = b - a
            length = float(np.linalg.norm(step))
            cache[key] = length < 1e-3 or (
                _push_pose(scene, obj, a, step / length, length) is not None
                and not any(
                    boxes_hit(footprint_at(scene, obj, a + t * step, scene.bbox(obj)[2] + 0.003), fixed, PUSH_TOLERANCE)
                    for t in (0.5, 1.0)
                )
            )
        return cache[key]

    stops = [here + d * np.array([math.cos(a), math.sin(a)]) for d in PUSH_DETOURS for a in np.arange(8) * math.pi / 4]
    plans = [[goal]]
    for stop in stops + [np.array([goal[0], here[1]]), np.array([here[0], goal[1]])]:
        plans.append([stop, goal])
        plans += [[stop, np.array([goal[0], stop[1]]), goal], [stop, np.array([stop[0], goal[1]]), goal]]
    best, best_length = [goal], np.inf
    for plan in plans:
        points = [here, *plan]
        length = sum(float(np.linalg.norm(b - a)) for a, b in zip(points, points[1:], strict=False)) + 0.05 * len(plan)
        if length < best_length and all(clear(a, b) for a, b in zip(points, points[1:], strict=False)):
            best, best_length = plan, length
    return best


def push_to(agent: Agent, obj: str, spot: Spot, *, tolerance: float = 0.01) -> Program:
    """Slide `obj` over the table until its origin is within `tolerance` of `spot`, pushing with the fingers."""
    stops = _push_plan(agent.scene, obj, spot.xy)
    for stop in stops:
        final = stop is stops[-1]
        for _ in range(3):
            scene = agent.scene
            to_go = stop - scene.pos(obj)[:2]
            if np.linalg.norm(to_go) < (tolerance if final else 0.02):
                break
            direction = to_go / np.linalg.norm(to_go)
            pose = _push_pose(scene, obj, scene.pos(obj)[:2], direction, float(np.linalg.norm(to_go)))
            start, rot = pose if pose is not None else _push_pose_upright(scene, obj, direction)
            yield from actuate(agent, CLOSE, max_steps=8)
            yield from reorient(agent, rot)
            scene = agent.scene
            path = flight_path(scene, scene.eef_pos, start + np.array([0.0, 0.0, 0.1]), hang=hand.TIP, reach=HAND_REACH)
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
                yield agent.command(np.array([*(scene.eef_pos[:2] + step), start[2]]), speed=0.5)
            yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, 0.06]), tol=0.02, steps=15)
    return bool(np.linalg.norm(spot.xy - agent.scene.pos(obj)[:2]) < tolerance)


def _push_pose_upright(scene: Scene, obj: str, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The upright pushing pose, used when no pose is clear (the best that can be done)."""
    box = scene.bbox(obj)
    corners = np.array([[x, y] for x in (box[0], box[3]) for y in (box[1], box[4])]) - scene.pos(obj)[:2]
    behind = float(np.max(-(corners @ direction)))
    start = scene.pos(obj)[:2] - direction * (behind + hand.FINGER_DEPTH + 0.008)
    yaw = wrap_half_turn(math.atan2(direction[1], direction[0]) + math.pi / 2, closing_yaw(scene.eef_mat))
    return np.array([*start, box[2] + hand.TIP + 0.006]), top_down(yaw)


def _door_contact(art, sense: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Where to push a hinged door: a point on its face trailing the motion, the motion's direction, mid-height."""
    boxes = art.boxes
    centres = boxes.centre[:, :2] - art.anchor[:2]
    arm = centres.mean(axis=0)
    arm /= np.linalg.norm(arm)
    length = float(np.max(centres @ arm))  # to the farthest part's centre
    radius = arm * length * DOOR_PUSH_AT
    tangent = np.cross([0.0, 0.0, sense], [radius[0], radius[1], 0.0])[:2]
    tangent /= np.linalg.norm(tangent)
    # The door's face on the trailing side, near the push point (the main slab, not a handle at its end).
    along = centres @ arm
    spread = np.sum(np.abs(np.einsum("nji,j->ni", boxes.rot, [arm[0], arm[1], 0.0])) * boxes.half, axis=1)
    near = np.abs(along - length * DOOR_PUSH_AT) <= spread
    local = np.abs(np.einsum("nji,j->ni", boxes.rot[near], [tangent[0], tangent[1], 0.0]))
    trailing = np.min(centres[near] @ tangent - np.sum(local * boxes.half[near], axis=1))
    point = art.anchor[:2] + radius + tangent * (trailing - radius @ tangent)
    height = float((boxes.aabb()[:, 2].min() + boxes.aabb()[:, 5].max()) / 2.0)
    return point, tangent, height


def close_door(agent: Agent, fixture: str) -> Program:
    """Swing a hinged door shut by pushing its face, from the side it moves away from, around the hinge."""
    art = agent.scene.articulation(fixture)
    goal = art.target("close")
    sense = float(np.sign(goal - art.qpos) * np.sign(art.axis[2]))
    point, tangent, height = _door_contact(art, sense)
    standoff = hand.FINGER_DEPTH + 0.015
    start = np.array([*(point - tangent * standoff), height])
    yaw = wrap_half_turn(math.atan2(tangent[1], tangent[0]) + math.pi / 2, closing_yaw(agent.scene.eef_mat))
    yield from actuate(agent, CLOSE, max_steps=8)
    yield from reorient(agent, top_down(yaw))
    path = flight_path(agent.scene, agent.scene.eef_pos, start + np.array([0.0, 0.0, 0.05]), hang=hand.TIP, reach=0.05)
    yield from travel(agent, start, path=path, rot=top_down(yaw), grip=CLOSE, tol=0.012)
    for _ in range(100):
        art = agent.scene.articulation(fixture)
        if art.reached("close"):
            break
        point, tangent, _ = _door_contact(art, sense)
        # Stay on the door's face and push along its motion; turn the hand with the door.
        aim = np.array([*(point - tangent * (standoff - 0.03)), height])
        yaw = wrap_half_turn(math.atan2(tangent[1], tangent[0]) + math.pi / 2, closing_yaw(agent.scene.eef_mat))
        yield agent.command(aim, rot=top_down(yaw), speed=0.6)
    yield from move(agent, agent.scene.eef_pos + np.array([0.0, 0.0, RETREAT]), tol=0.02, steps=20)
    return agent.scene.articulation(fixture).holds("close")
