"""Choosing a top-down grasp from an object's collision boxes.

Candidates are lines through the object's centre at several yaws. Along each line the object's
material (within a thin strip, at the height the finger pads will be) forms segments; a segment
narrow enough for the pads is a grasp: the one containing the centre is a centre grasp (a can, a
box), one off-centre is a rim or edge grasp (the wall of a bowl or a mug). A candidate is kept when
the fingers and the palm are clear of everything else at the object and where it will be placed;
the cheapest (least wrist rotation, centre before rim, most clearance) wins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.geometry import closing_yaw, overlap_volume, top_down, transform_boxes, wrap_half_turn
from langgap.policies.oracle.scene import Scene

YAW_STEPS = 12  # candidate closing axes, every 15 degrees over a half turn
STRIP = 0.008  # half-width of the strip of material the pads close on
GRASP_DEPTH = 0.023  # grip site below the object's top (the palm must stay above the top)
MIN_TIP_CLEARANCE = 0.002  # finger tips above the object's bottom (the table)
COLLISION_TOLERANCE = 2e-7  # m^3 of overlap ignored (mesh boxes are conservative)
RIM_COST = 0.6  # preference for centre grasps, in radians of wrist rotation
CLEARANCE_WEIGHT = 20.0  # cost per metre of missing clearance around the fingers
WANTED_CLEARANCE = 0.02
COMFORTABLE_REACH = 0.62  # horizontal distance from the robot's base beyond which the arm nears full stretch
REACH_WEIGHT = 25.0  # cost per metre beyond the comfortable reach


@dataclass(frozen=True)
class Grasp:
    """A top-down grasp: the grip-site position, the closing yaw, and the material width between the pads."""

    point: np.ndarray
    yaw: float
    width: float
    rim: bool
    cost: float

    @property
    def rot(self) -> np.ndarray:
        return top_down(self.yaw)


def _segments(boxes: np.ndarray, origin: np.ndarray, direction: np.ndarray) -> list[tuple[float, float]]:
    """Merged intervals (along `direction` from `origin`) where `boxes` cross a thin strip on that line."""
    normal = np.array([-direction[1], direction[0]])
    intervals = []
    for box in boxes:
        corners = np.array([[x, y] for x in (box[0], box[3]) for y in (box[1], box[4])]) - origin
        across = corners @ normal
        if across.min() > STRIP or across.max() < -STRIP:
            continue
        along = corners @ direction
        intervals.append((float(along.min()), float(along.max())))
    intervals.sort()
    merged: list[list[float]] = []
    for lo, hi in intervals:
        if merged and lo <= merged[-1][1] + 1e-4:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([lo, hi])
    return [(lo, hi) for lo, hi in merged]


def grasp_height(boxes: np.ndarray) -> float:
    """Grip-site height for a top-down grasp of an object made of `boxes` (world AABBs)."""
    top, bottom = boxes[:, 5].max(), boxes[:, 2].min()
    return max(top - GRASP_DEPTH, bottom + hand.TIP + MIN_TIP_CLEARANCE)


def pad_span(z: float) -> tuple[float, float]:
    """World heights (low, high) the pads of a top-down gripper with its grip site at `z` cover."""
    centre = z - hand.PAD_CENTRE
    return centre - hand.PAD_HALF_HEIGHT, centre + hand.PAD_HALF_HEIGHT


def hand_boxes(point: np.ndarray, yaw: float, width: float = hand.PAD_GAP_OPEN) -> np.ndarray:
    """World AABBs of the fingers and the palm of a top-down gripper at `point`."""
    local = np.concatenate([hand.finger_boxes(width), hand.palm_box()])
    return transform_boxes(local, top_down(yaw), point)


def _collision(point: np.ndarray, yaw: float, obstacles: np.ndarray, approach: float) -> float:
    """Overlap volume of the open hand (swept down from `approach` above `point`) with `obstacles`."""
    boxes = hand_boxes(point, yaw)
    boxes[:, 5] += approach
    return sum(overlap_volume(box, obstacles) for box in boxes)


def _clearance(point: np.ndarray, yaw: float, obstacles: np.ndarray) -> float:
    """How far (up to WANTED_CLEARANCE) the open fingers are from the nearest obstacle."""
    fingers = hand_boxes(point, yaw)[:2]
    for margin in np.linspace(0.0, WANTED_CLEARANCE, 5)[1:]:
        grown = fingers + np.array([-margin, -margin, 0.0, margin, margin, 0.0])
        if any(overlap_volume(box, obstacles) > COLLISION_TOLERANCE for box in grown):
            return float(margin)
    return WANTED_CLEARANCE


def plan_grasp(
    scene: Scene,
    obj: str,
    *,
    place_shift: np.ndarray | None = None,
    place_obstacles: np.ndarray | None = None,
    approach: float = 0.08,
) -> Grasp | None:
    """The best top-down grasp of `obj`, or None if none fits.

    `place_shift` moves the object from its current pose to where it will be released; with
    `place_obstacles` the hand is also checked there, so a grasp that would hit the target's
    surroundings (a drawer, a basket wall) is not chosen.
    """
    boxes = scene.world_shape(obj)
    z = grasp_height(boxes)
    pad_lo, pad_hi = pad_span(z)
    pads = boxes[(boxes[:, 2] < pad_hi) & (boxes[:, 5] > pad_lo)]
    if len(pads) == 0:
        return None
    centre = (pads[:, :2].min(axis=0) + pads[:, 3:5].max(axis=0)) / 2.0
    own_below = boxes[boxes[:, 5] <= pad_lo]  # e.g. a bowl's floor under the fingers
    around = scene.obstacles(exclude=(obj,))
    obstacles = np.concatenate([around, own_below]) if len(own_below) else around
    current = closing_yaw(scene.eef_mat)
    best: Grasp | None = None
    for k in range(YAW_STEPS):
        yaw = wrap_half_turn(k * math.pi / YAW_STEPS, current)
        direction = np.array([math.cos(yaw), math.sin(yaw)])
        for lo, hi in _segments(pads, centre, direction):
            width = hi - lo
            if width > hand.MAX_GRASP_WIDTH:
                continue
            mid = (lo + hi) / 2.0
            rim = not lo - 1e-3 <= 0.0 <= hi + 1e-3
            point = np.array([*(centre + mid * direction), z])
            # The other parts of this object in the finger span must stay outside the pads.
            others = [s for s in _segments(pads, centre, direction) if s != (lo, hi)]
            reach = hand.PAD_GAP_OPEN / 2 + hand.FINGER_THICKNESS
            if any(s_hi > mid - reach and s_lo < mid + reach for s_lo, s_hi in others):
                continue
            if _collision(point, yaw, obstacles, approach) > COLLISION_TOLERANCE:
                continue
            cost = abs(yaw - current) + (RIM_COST if rim else 0.0)
            cost += CLEARANCE_WEIGHT * (WANTED_CLEARANCE - _clearance(point, yaw, obstacles))
            cost += REACH_WEIGHT * max(0.0, scene.reach(point) - COMFORTABLE_REACH)
            if place_shift is not None and place_obstacles is not None:
                at_place = point + place_shift
                cost += 1e6 * max(0.0, _collision(at_place, yaw, place_obstacles, approach) - COLLISION_TOLERANCE)
                cost += REACH_WEIGHT * max(0.0, scene.reach(at_place) - COMFORTABLE_REACH)
            if best is None or cost < best.cost:
                best = Grasp(point=point, yaw=yaw, width=width, rim=rim, cost=cost)
    return best
