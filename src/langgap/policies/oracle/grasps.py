"""Choosing a top-down grasp from an object's collision boxes.

Candidates are lines through the object's centre at several yaws. Along each line the object's
material (within a thin strip, at the height the finger pads will be) forms segments; a segment
narrow enough for the pads is a grasp: the one containing the centre is a centre grasp (a can, a
box), one off-centre is a rim or edge grasp (the wall of a bowl or a mug). A candidate is kept when
the fingers and the palm are clear of everything else, at the object and where it will be placed;
the cheapest (least wrist rotation, centre before rim, most clearance, least stretch of the arm)
wins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.geometry import Boxes, hand_yaw, penetration, top_down, wrist_yaw
from langgap.policies.oracle.scene import Scene

YAW_STEPS = 12  # candidate closing axes, every 15 degrees over a half turn
STRIP = 0.008  # half-width of the strip of material the pads close on
GRASP_DEPTHS = (0.027, 0.02, 0.014)  # grip site below the object's top, deepest first (the palm stays above)
SHALLOW_COST = 20.0  # per metre of depth given up
MIN_TIP_CLEARANCE = 0.002  # finger tips above the object's bottom (the table)
PENETRATION_TOLERANCE = 0.0015  # metres of overlap ignored (collision boxes are conservative)
NUDGE_LIMIT = 0.012  # the palm may brush a loose object this deep (it gets nudged), at a cost
NUDGE_WEIGHT = 150.0  # cost per metre of such overlap
UNPLACEABLE_COST = 10.0  # a grasp whose hand would collide where the object is released
OFF_CENTRE_WEIGHT = 13.0  # cost per metre between the grasp and the middle of the object (radians of wrist turn)
LINE_SPACING = 0.01  # between parallel grasp lines
OFFSET_WEIGHT = 40.0  # cost per metre a grasp line passes beside the object's middle (an oblique cut of a wall)
CLEARANCE_WEIGHT = 20.0  # cost per metre of missing clearance around the fingers
WANTED_CLEARANCE = 0.02
COMFORTABLE_REACH = 0.62  # horizontal distance from the robot's base beyond which the arm nears full stretch
REACH_WEIGHT = 25.0  # cost per metre beyond the comfortable reach
FULL_STRETCH = 0.70  # beyond this the arm, moving fast, can lock its elbow straight and stall
STRETCH_WEIGHT = 50.0  # further cost per metre beyond FULL_STRETCH


APPROACHES = (0.05, 0.035, 0.025, 0.015)  # pre-grasp heights above the grasp, highest first
SIDE_STEP = 0.07  # a low approach enters sideways from this far
SIDE_DIRECTIONS = 8
SIDE_COST = 0.5


@dataclass(frozen=True)
class Grasp:
    """A top-down grasp: the grip-site position, the closing yaw, the material width between the pads,
    and the waypoints that lead the open hand to it (the first is reached from straight above)."""

    point: np.ndarray
    yaw: float
    width: float
    rim: bool
    cost: float
    entry: tuple[np.ndarray, ...] = ()
    placeable: bool = True  # the hand fits where the object will be released

    @property
    def rot(self) -> np.ndarray:
        return top_down(self.yaw)


def footprint_corners(boxes: Boxes) -> np.ndarray:
    """The four horizontal corners (n, 4, 2) of each box's footprint (boxes rotated about z only)."""
    signs = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]], dtype=np.float64)
    axes = boxes.rot[:, :2, :2]  # the xy part of the box's x and y axes (columns)
    offsets = np.einsum("nij,kj,nj->nki", axes, signs, boxes.half[:, :2])
    return boxes.centre[:, None, :2] + offsets


def _segments(boxes: Boxes, origin: np.ndarray, direction: np.ndarray) -> list[tuple[float, float]]:
    """Merged intervals (along `direction` from `origin`) where `boxes` cross a thin strip on that line."""
    if len(boxes) == 0:
        return []
    normal = np.array([-direction[1], direction[0]])
    corners = footprint_corners(boxes) - origin
    across = corners @ normal
    crossing = (across.min(axis=1) <= STRIP) & (across.max(axis=1) >= -STRIP)
    along = corners[crossing] @ direction
    intervals = sorted(zip(along.min(axis=1), along.max(axis=1), strict=True))
    merged: list[list[float]] = []
    for lo, hi in intervals:
        if merged and lo <= merged[-1][1] + 1e-4:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([float(lo), float(hi)])
    return [(lo, hi) for lo, hi in merged]


def grasp_height(bounds: np.ndarray, depth: float = GRASP_DEPTHS[0]) -> float:
    """Grip-site height for a top-down grasp `depth` below the top of an object with world bounds (n, 6)."""
    top, bottom = bounds[:, 5].max(), bounds[:, 2].min()
    return max(top - depth, bottom + hand.TIP + MIN_TIP_CLEARANCE)


def pad_span(z: float) -> tuple[float, float]:
    """World heights (low, high) the pads of a top-down gripper with its grip site at `z` cover."""
    centre = z - hand.PAD_CENTRE
    return centre - hand.PAD_HALF_HEIGHT, centre + hand.PAD_HALF_HEIGHT


def hand_boxes(point: np.ndarray, yaw: float, *, width: float = hand.PAD_GAP_OPEN, sweep: float = 0.0) -> Boxes:
    """The fingers and the palm of a top-down gripper at `point`, swept up by `sweep` (its approach)."""
    local = hand.local_boxes(width)
    local[:, 2] -= sweep  # the site frame's z points down: sweeping up extends the boxes to lower z
    return Boxes.from_local(local, top_down(yaw), point)


def hand_depth(point: np.ndarray, yaw: float, obstacles: Boxes, *, sweep: float = 0.0, grow: float = 0.0) -> float:
    """How deep the open hand at `point` (swept down from `sweep` above) overlaps `obstacles` (<= 0: clear)."""
    boxes = hand_boxes(point, yaw, sweep=sweep)
    deepest = -np.inf
    for index, (centre, half, rot) in enumerate(zip(boxes.centre, boxes.half, boxes.rot, strict=True)):
        margin = grow if index < 2 else 0.0  # only the fingers are grown when measuring clearance
        depth = penetration(centre, half + np.array([margin, margin, 0.0]), rot, obstacles)
        if len(depth):
            deepest = max(deepest, float(depth.max()))
    return deepest


def hand_hits(point: np.ndarray, yaw: float, obstacles: Boxes, *, sweep: float = 0.0, grow: float = 0.0) -> bool:
    """Whether the open hand at `point` (swept down from `sweep` above) touches `obstacles`."""
    return hand_depth(point, yaw, obstacles, sweep=sweep, grow=grow) > PENETRATION_TOLERANCE


def approach_path(
    point: np.ndarray, yaw: float, obstacles: Boxes, approach: float, lowest: float = 0.0
) -> tuple[np.ndarray, ...] | None:
    """Waypoints leading the open hand down to `point`, or None if it cannot get there.

    Straight down from `approach` above when that is clear; otherwise down to the highest clear
    pre-grasp height (at least `lowest`, where the finger tips clear the object) from a point
    beside it, then sideways (something overhangs the object, e.g. an open drawer).
    """
    if not hand_hits(point, yaw, obstacles, sweep=approach):
        return (point + np.array([0.0, 0.0, approach]),)
    for height in APPROACHES[1:]:
        if height < lowest or hand_hits(point, yaw, obstacles, sweep=height):
            continue
        low = point + np.array([0.0, 0.0, height])
        for k in range(SIDE_DIRECTIONS):
            angle = 2 * math.pi * k / SIDE_DIRECTIONS
            side = low + SIDE_STEP * np.array([math.cos(angle), math.sin(angle), 0.0])
            if hand_hits(side, yaw, obstacles, sweep=approach):
                continue
            steps = np.linspace(0.0, 1.0, 5)[1:-1]
            if any(hand_hits(side + t * (low - side), yaw, obstacles) for t in steps):
                continue
            return (side + np.array([0.0, 0.0, approach]), side, low)
        return None
    return None


def _clearance(point: np.ndarray, yaw: float, obstacles: Boxes) -> float:
    """How far (up to WANTED_CLEARANCE) the open fingers are from the nearest obstacle."""
    for margin in np.linspace(0.0, WANTED_CLEARANCE, 5)[1:]:
        if hand_hits(point, yaw, obstacles, grow=float(margin)):
            return float(margin)
    return WANTED_CLEARANCE


@dataclass(frozen=True)
class _Candidate:
    point: np.ndarray
    yaw: float
    width: float
    rim: bool
    cost: float  # the part of the cost known before any collision check
    own: Boxes  # the object's own parts the hand must not touch


def stretch_cost(scene: Scene, point: np.ndarray) -> float:
    """The cost of holding the hand at `point`, rising steeply as the arm nears full stretch."""
    reach = scene.reach(point)
    return REACH_WEIGHT * max(0.0, reach - COMFORTABLE_REACH) + STRETCH_WEIGHT * max(0.0, reach - FULL_STRETCH)


def has_grasp(scene: Scene, obj: str) -> bool:
    """Whether `obj` has any part narrow enough to grasp at all (before checking for collisions)."""
    bounds = scene.boxes(obj).aabb()
    return any(True for _ in _candidates(scene, scene.boxes(obj), bounds))


def plan_grasp(
    scene: Scene,
    obj: str,
    *,
    place_shift: np.ndarray | None = None,
    place_obstacles: Boxes | None = None,
    approach: float = APPROACHES[0],
) -> Grasp | None:
    """The best top-down grasp of `obj`, or None if none fits.

    `place_shift` moves the object from its current pose to where it will be released; with
    `place_obstacles` the hand is also checked there, so a grasp that would hit the target's
    surroundings (a drawer's walls, a basket's rim) is avoided. Candidates are checked for
    collisions cheapest first, and the search stops once no unchecked one can win.
    """
    boxes = scene.boxes(obj)
    bounds = boxes.aabb()
    fixed = scene.obstacles(exclude=(obj,), fixtures_only=True)
    loose = scene.loose_boxes(exclude=(obj,))
    candidates = sorted(_candidates(scene, boxes, bounds), key=lambda c: c.cost)
    placing = place_shift is not None and place_obstacles is not None
    lowest = {}
    best: Grasp | None = None
    for candidate in candidates:
        if best is not None and candidate.cost >= best.cost:
            break
        placeable, penalty, stretch = True, 0.0, 0.0
        if placing:
            at_place = candidate.point + place_shift
            stretch = stretch_cost(scene, at_place)
            # The costs at the place are known before the (costly) collision checks at the object, and
            # those only add to a cost: a candidate already no cheaper than the best cannot win.
            if best is not None and candidate.cost + stretch >= best.cost:
                continue
            placeable = not hand_hits(at_place, candidate.yaw, place_obstacles)
            penalty = 0.0 if placeable else UNPLACEABLE_COST  # still possible, but only if nothing else is
            if best is not None and candidate.cost + penalty + stretch >= best.cost:
                continue
        z = candidate.point[2]
        if z not in lowest:
            lowest[z] = bounds[:, 5].max() - z + hand.TIP + 0.005
        grasp = _evaluate(scene, candidate, fixed, loose, approach, lowest[z])
        if grasp is None:
            continue
        cost = grasp.cost + penalty + stretch
        if best is None or cost < best.cost:
            best = Grasp(grasp.point, grasp.yaw, grasp.width, grasp.rim, cost, grasp.entry, placeable)
    return best


def _candidates(scene: Scene, boxes: Boxes, bounds: np.ndarray):
    """Every grasp line (yaw, offset) at every depth whose material between the pads is narrow enough."""
    current = hand_yaw(scene.eef_mat)
    reach = hand.PAD_GAP_OPEN / 2 + hand.FINGER_THICKNESS
    corners_all = footprint_corners(boxes)
    for depth in GRASP_DEPTHS:
        z = grasp_height(bounds, depth)
        pad_lo, pad_hi = pad_span(z)
        at_pads = (bounds[:, 2] < pad_hi) & (bounds[:, 5] > pad_lo)
        if not at_pads.any():
            continue
        pads = boxes.select(at_pads)
        pad_bounds = bounds[at_pads]
        centre = (pad_bounds[:, :2].min(axis=0) + pad_bounds[:, 3:5].max(axis=0)) / 2.0
        standing = bounds[:, 5] > pad_lo
        below = boxes.select(~standing)  # e.g. a bowl's floor under the fingers
        azimuth = scene.azimuth(centre)
        for k in range(YAW_STEPS):
            yaw = wrist_yaw(k * math.pi / YAW_STEPS, current, azimuth)
            direction = np.array([math.cos(yaw), math.sin(yaw)])
            normal = np.array([-direction[1], direction[0]])
            across = (footprint_corners(pads) - centre) @ normal
            offsets = np.arange(across.min() + STRIP, across.max() - STRIP + 1e-9, LINE_SPACING)
            for offset in np.unique(np.round(np.append(offsets, 0.0), 4)):
                origin = centre + offset * normal
                segments = _segments(pads, origin, direction)
                for lo, hi in segments:
                    width = hi - lo
                    mid = (lo + hi) / 2.0
                    if width > hand.MAX_GRASP_WIDTH or any(
                        s_hi > mid - reach and s_lo < mid + reach for s_lo, s_hi in segments if (s_lo, s_hi) != (lo, hi)
                    ):
                        continue
                    point = np.array([*(origin + mid * direction), z])
                    # The object's parts outside the strip between the pads are obstacles for the hand.
                    rel = corners_all - origin
                    along, side = rel @ direction, rel @ normal
                    gripped = (
                        (side.min(axis=1) <= STRIP)
                        & (side.max(axis=1) >= -STRIP)
                        & (along.min(axis=1) <= hi)
                        & (along.max(axis=1) >= lo)
                    )
                    own = Boxes.concat([below, boxes.select(standing & ~gripped)])
                    off_centre = float(np.linalg.norm(point[:2] - centre))
                    centred = lo - 1e-3 <= float(np.dot(centre - origin, direction)) <= hi + 1e-3
                    rim = not centred or abs(offset) > STRIP
                    cost = abs(yaw - current) + OFF_CENTRE_WEIGHT * off_centre + OFFSET_WEIGHT * abs(offset)
                    cost += SHALLOW_COST * (GRASP_DEPTHS[0] - depth)
                    cost += stretch_cost(scene, point)
                    yield _Candidate(point=point, yaw=yaw, width=width, rim=rim, cost=cost, own=own)


def _evaluate(
    scene: Scene, candidate: _Candidate, fixed: Boxes, loose: Boxes, approach: float, lowest: float
) -> Grasp | None:
    """The candidate as a grasp with its full cost, or None if the hand cannot get there.

    The hand may brush loose objects (they get nudged) up to NUDGE_LIMIT deep, at a cost.
    """
    point, yaw = candidate.point, candidate.yaw
    obstacles = Boxes.concat([fixed, candidate.own])
    entry = approach_path(point, yaw, obstacles, approach, lowest=lowest)
    if entry is None:
        return None
    nudge = max(0.0, hand_depth(point, yaw, loose, sweep=entry[-1][2] - point[2]))
    if nudge > NUDGE_LIMIT:
        return None
    cost = candidate.cost + NUDGE_WEIGHT * nudge + SIDE_COST * (len(entry) > 1)
    cost += CLEARANCE_WEIGHT * (WANTED_CLEARANCE - _clearance(point, yaw, Boxes.concat([obstacles, loose])))
    return Grasp(point=point, yaw=yaw, width=candidate.width, rim=candidate.rim, cost=cost, entry=entry)
