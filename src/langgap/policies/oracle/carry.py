"""The hand with its load as one collision body, and how to bring it down onto a spot.

Most spots are reached by a vertical descent. A spot under something (a drawer's spot under the
cabinet's front, a microwave's shelf) is reached from the side: down beside it, then across.
"""

from __future__ import annotations

import math

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.geometry import Boxes, boxes_hit
from langgap.policies.oracle.scene import Scene

TOLERANCE = 0.002
SWEEP_STEP = 0.02
SIDE_DISTANCES = (0.04, 0.07, 0.1, 0.13)
SIDE_DIRECTIONS = 12
RISE = 0.12  # how high above the release point a route starts


def load_boxes(scene: Scene, obj: str, eef: np.ndarray, rot: np.ndarray) -> Boxes:
    """The hand (fingers at their current opening) and its load's bounds, with the grip site moved to `eef`."""
    bounds = scene.bbox(obj)
    shift = eef - scene.eef_pos
    load = Boxes.from_local((bounds + np.tile(shift, 2))[None, :], np.eye(3), np.zeros(3))
    local = hand.local_boxes(max(scene.gripper_width, 0.0))
    return Boxes.concat([load, Boxes.from_local(local, rot, eef)])


def _clear(scene: Scene, obj: str, eef: np.ndarray, rot: np.ndarray, obstacles: Boxes, rise: float = 0.0) -> bool:
    """Whether the hand and load at `eef`, and on the way straight up by `rise`, touch nothing."""
    for lift in np.arange(0.0, rise + 1e-9, SWEEP_STEP):
        if boxes_hit(load_boxes(scene, obj, eef + np.array([0.0, 0.0, lift]), rot), obstacles, TOLERANCE):
            return False
    return True


def _turn(angle: float, reference: float) -> float:
    return abs(math.remainder(angle - reference, 2 * math.pi))


def release_route(scene: Scene, obj: str, release: np.ndarray, rot: np.ndarray, clearance: float) -> list[np.ndarray]:
    """Grip-site waypoints ending at `release` (the hand and load just above the spot).

    The route goes straight down from `clearance` above the spot, or, when something overhangs
    the spot, down from `RISE` above a point beside it and then across. If neither is clear, the
    vertical route is returned anyway.
    """
    obstacles = scene.obstacles(exclude=(obj,))
    up = np.array([0.0, 0.0, RISE])
    if _clear(scene, obj, release, rot, obstacles, rise=RISE):
        return [release + np.array([0.0, 0.0, clearance]), release]
    base = scene.base_pos[:2] - release[:2]
    toward_base = math.atan2(base[1], base[0])
    for distance in SIDE_DISTANCES:
        # Directions nearest the robot first: the arm is least stretched there.
        for k in sorted(range(SIDE_DIRECTIONS), key=lambda k: _turn(2 * math.pi * k / SIDE_DIRECTIONS, toward_base)):
            angle = 2 * math.pi * k / SIDE_DIRECTIONS
            side = release + distance * np.array([math.cos(angle), math.sin(angle), 0.0])
            if not _clear(scene, obj, side, rot, obstacles, rise=RISE):
                continue
            steps = np.linspace(0.0, 1.0, max(2, int(distance / SWEEP_STEP) + 1))[1:-1]
            if all(_clear(scene, obj, side + t * (release - side), rot, obstacles) for t in steps):
                return [side + up, side, release]
    return [release + np.array([0.0, 0.0, clearance]), release]
