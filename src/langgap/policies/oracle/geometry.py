"""Small rigid-body helpers: rotations, top-down gripper frames and axis-aligned boxes."""

from __future__ import annotations

import math

import numpy as np


def quat_to_mat(quat_wxyz: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion given as (w, x, y, z), MuJoCo's order."""
    w, x, y, z = quat_wxyz
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def mat_to_axis_angle(rot: np.ndarray) -> np.ndarray:
    """The rotation vector (axis * angle) of a rotation matrix."""
    cos = min(max((np.trace(rot) - 1.0) / 2.0, -1.0), 1.0)
    angle = math.acos(cos)
    if angle < 1e-9:
        return np.zeros(3)
    if math.pi - angle < 1e-6:
        # Near a half turn the antisymmetric part vanishes; read the axis from the symmetric part.
        axis = np.sqrt(np.clip((np.diag(rot) + 1.0) / 2.0, 0.0, None))
        axis[1] = math.copysign(axis[1], rot[0, 1] + rot[1, 0])
        axis[2] = math.copysign(axis[2], rot[0, 2] + rot[2, 0])
        return axis / np.linalg.norm(axis) * angle
    vec = np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]])
    return vec / (2.0 * math.sin(angle)) * angle


def rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix of `angle` radians about unit `axis`."""
    x, y, z = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    return np.array(
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    )


def top_down(yaw: float) -> np.ndarray:
    """Gripper frame pointing straight down whose fingers close along world (cos yaw, sin yaw, 0).

    The Panda grip site's x axis is the finger-closing axis and its z axis the approach axis.
    """
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])


def closing_yaw(rot: np.ndarray) -> float:
    """The yaw of the finger-closing axis of gripper frame `rot`."""
    return math.atan2(rot[1, 0], rot[0, 0])


def wrap_half_turn(yaw: float, reference: float) -> float:
    """`yaw` or `yaw + pi` (a parallel gripper is symmetric), whichever is nearer `reference`."""
    best = yaw
    for candidate in (yaw - math.pi, yaw + math.pi, yaw - 2 * math.pi, yaw + 2 * math.pi):
        if abs(candidate - reference) < abs(best - reference):
            best = candidate
    return best


def box_corners(box: np.ndarray) -> np.ndarray:
    """The 8 corners (8, 3) of an axis-aligned box (min xyz, max xyz)."""
    lo, hi = box[:3], box[3:]
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def transform_boxes(boxes: np.ndarray, rot: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """World AABBs (n, 6) of body-frame boxes (n, 6) of a body at pose (rot, pos)."""
    if len(boxes) == 0:
        return np.zeros((0, 6))
    centre = (boxes[:, :3] + boxes[:, 3:]) / 2.0
    half = (boxes[:, 3:] - boxes[:, :3]) / 2.0
    world_centre = centre @ rot.T + pos
    world_half = half @ np.abs(rot).T
    return np.concatenate([world_centre - world_half, world_centre + world_half], axis=1)


def oriented_box(centre: np.ndarray, half: np.ndarray, yaw: float) -> np.ndarray:
    """World AABB of a box with `half` extents (along its x, y, z) rotated by `yaw` about z."""
    return transform_boxes(np.concatenate([-half, half])[None, :], top_down_yaw_only(yaw), centre)[0]


def top_down_yaw_only(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def boxes_overlap(box: np.ndarray, others: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """Per row of `others` (n, 6): whether it intersects `box` grown by `margin`."""
    if len(others) == 0:
        return np.zeros(0, dtype=bool)
    lo, hi = box[:3] - margin, box[3:] + margin
    return np.all((others[:, :3] < hi) & (others[:, 3:] > lo), axis=1)


def overlap_volume(box: np.ndarray, others: np.ndarray) -> float:
    """Total volume of the intersections of `box` with each row of `others`."""
    if len(others) == 0:
        return 0.0
    lo = np.maximum(others[:, :3], box[:3])
    hi = np.minimum(others[:, 3:], box[3:])
    return float(np.prod(np.clip(hi - lo, 0.0, None), axis=1).sum())
