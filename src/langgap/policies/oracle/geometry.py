"""Small rigid-body helpers: rotations, top-down gripper frames and oriented boxes."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

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


START_YAW = math.pi / 2  # the closing yaw of the (top-down) hand when an episode starts
DOWNWARD = -0.7  # a hand whose approach axis points lower than this (z) points down, leaning or not


def hand_yaw(rot: np.ndarray) -> float:
    """The closing yaw to measure the next turn of a hand with frame `rot` from: its own while it
    points down; the start's when it does not (a hand that pulled a drawer closes vertically, its
    closing axis has no yaw to keep)."""
    if rot[2, 2] > DOWNWARD:
        return START_YAW
    return math.atan2(rot[1, 0], rot[0, 0])


def leaning(rot: np.ndarray, toward: np.ndarray, angle: float) -> np.ndarray:
    """Gripper frame `rot` turned about its closing axis so its fingers point `angle` radians toward `toward`."""
    axis = rot[:, 0]
    turned = rotation_about(axis, angle) @ rot
    return turned if np.dot(turned[:, 2], toward) > 0 else rotation_about(axis, -angle) @ rot


def bounds_corners_xy(bounds: np.ndarray) -> np.ndarray:
    """The four horizontal corners (4, 2) of axis-aligned bounds (min xyz, max xyz)."""
    return np.array([[x, y] for x in (bounds[0], bounds[3]) for y in (bounds[1], bounds[4])])


def bounds_xy(bounds: np.ndarray, origin: np.ndarray | None = None) -> np.ndarray:
    """The horizontal rectangle (x/y lo, x/y hi) of axis-aligned bounds (min xyz, max xyz), relative to
    `origin` (x, y) when given."""
    rect = bounds[[0, 1, 3, 4]]
    return rect if origin is None else rect - np.tile(origin[:2], 2)


def wrap_half_turn(yaw: float, reference: float) -> float:
    """`yaw` or `yaw + pi` (a parallel gripper is symmetric), whichever is nearer `reference`."""
    best = yaw
    for candidate in (yaw - math.pi, yaw + math.pi, yaw - 2 * math.pi, yaw + 2 * math.pi):
        if abs(candidate - reference) < abs(best - reference):
            best = candidate
    return best


# The Panda's last joint, for a top-down hand: its angle is about WRIST_ZERO minus (the closing yaw
# minus the hand's azimuth from the base), measured; its range is +-2.9 rad, kept with a margin.
WRIST_ZERO = 2.35
WRIST_LIMIT = 2.6


def wrist_angle(yaw: float, azimuth: float) -> float:
    """The estimated angle of the Panda's last joint for a top-down hand closing along `yaw` at `azimuth`."""
    return math.remainder(WRIST_ZERO - (yaw - azimuth), 2 * math.pi)


def wrist_yaw(yaw: float, reference: float, azimuth: float) -> float:
    """`yaw` or `yaw + pi` for a top-down hand at `azimuth` (radians, seen from the robot's base):
    the one nearer `reference`, unless it would turn the wrist's last joint past its limit, where
    the controller stalls."""
    best = wrap_half_turn(yaw, reference)
    if abs(wrist_angle(best, azimuth)) > WRIST_LIMIT:
        best += math.pi if best < reference else -math.pi
    return best


def sweeping_yaw(yaw: float, azimuth: float, sweep: float) -> float:
    """`yaw` or `yaw + pi` for a top-down hand at `azimuth` that will turn by `sweep` radians while it
    works (following a door round its hinge): the one that keeps the wrist's last joint furthest from
    its limits over the whole turn. Turning the other way round ends against a limit mid-push."""

    def worst(candidate: float) -> float:
        start = wrist_angle(candidate, azimuth)
        return max(abs(start), abs(start - sweep))  # the joint turns against the hand's yaw

    return min((yaw, yaw + math.pi), key=worst)


@dataclass(frozen=True)
class Boxes:
    """Oriented boxes: centres (n, 3), half extents (n, 3) and rotations (n, 3, 3) (columns = box axes)."""

    centre: np.ndarray
    half: np.ndarray
    rot: np.ndarray

    @staticmethod
    def empty() -> Boxes:
        return Boxes(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3, 3)))

    @staticmethod
    def from_local(local: np.ndarray, rot: np.ndarray, pos: np.ndarray) -> Boxes:
        """Boxes given as (min xyz, max xyz) rows in the frame of a body at pose (rot, pos)."""
        local = np.asarray(local, dtype=np.float64).reshape(-1, 6)
        centre = (local[:, :3] + local[:, 3:]) / 2.0 @ rot.T + pos
        half = (local[:, 3:] - local[:, :3]) / 2.0
        return Boxes(centre, half, np.repeat(rot[None, :, :], len(local), axis=0))

    @staticmethod
    def concat(parts: list[Boxes]) -> Boxes:
        parts = [p for p in parts if len(p)]
        if not parts:
            return Boxes.empty()
        return Boxes(*(np.concatenate([getattr(p, f) for p in parts]) for f in ("centre", "half", "rot")))

    def __len__(self) -> int:
        return len(self.centre)

    def select(self, mask: np.ndarray) -> Boxes:
        return Boxes(self.centre[mask], self.half[mask], self.rot[mask])

    def shifted(self, offset: np.ndarray) -> Boxes:
        return Boxes(self.centre + offset, self.half, self.rot)

    def extent(self, along: np.ndarray) -> np.ndarray:
        """Each box's half-extent along the unit vector `along` (n,)."""
        return np.sum(np.abs(np.einsum("nji,j->ni", self.rot, along)) * self.half, axis=1)

    def aabb(self) -> np.ndarray:
        """World axis-aligned bounds (n, 6)."""
        return self._bounds

    @cached_property
    def _bounds(self) -> np.ndarray:
        extent = np.einsum("nij,nj->ni", np.abs(self.rot), self.half)
        return np.concatenate([self.centre - extent, self.centre + extent], axis=1)

    def under(self, xy: np.ndarray, radius: float = 0.0) -> np.ndarray:
        """Which boxes' footprints (in their own frames) contain the point `xy`, grown by `radius`."""
        offset = np.zeros((len(self), 3))
        offset[:, :2] = np.asarray(xy)[None, :2] - self.centre[:, :2]
        local = np.einsum("nji,nj->ni", self.rot, offset)
        return np.all(np.abs(local[:, :2]) <= self.half[:, :2] + radius, axis=1)


def penetration(centre: np.ndarray, half: np.ndarray, rot: np.ndarray, others: Boxes) -> np.ndarray:
    """How deep one oriented box overlaps each of `others` (separating-axis test); <= 0 means apart.

    Boxes whose axis-aligned bounds do not meet get a (negative) bound gap instead of the full test.
    """
    if len(others) == 0:
        return np.zeros(0)
    extent = np.abs(rot) @ half
    bounds = others.aabb()
    gaps = np.maximum(bounds[:, :3] - (centre + extent), (centre - extent) - bounds[:, 3:]).max(axis=1)
    result = -np.maximum(gaps, 1e-9)
    close = np.flatnonzero(gaps < 0.0)
    if len(close) == 0:
        return result
    near = others.select(close)
    n = len(near)
    axes_a = np.repeat(rot.T[None, :, :], n, axis=0)  # (n, 3, 3): rows are A's axes
    axes_b = np.transpose(near.rot, (0, 2, 1))  # rows are B's axes
    cross = np.cross(axes_a[:, :, None, :], axes_b[:, None, :, :]).reshape(n, 9, 3)
    axes = np.concatenate([axes_a, axes_b, cross], axis=1)  # (n, 15, 3)
    norm = np.linalg.norm(axes, axis=2)
    valid = norm > 1e-6
    axes = axes / np.where(valid, norm, 1.0)[:, :, None]
    radius_a = np.abs(np.einsum("nkj,ji->nki", axes, rot)) @ half
    radius_b = np.einsum("nki,ni->nk", np.abs(np.einsum("nkj,nji->nki", axes, near.rot)), near.half)
    distance = np.abs(np.einsum("nkj,nj->nk", axes, near.centre - centre[None, :]))
    overlap = np.where(valid, radius_a + radius_b - distance, np.inf)
    result[close] = overlap.min(axis=1)
    return result


def depth(boxes: Boxes, others: Boxes) -> float:
    """How deep the deepest of `boxes` penetrates any of `others` (<= 0 when apart)."""
    parts = zip(boxes.centre, boxes.half, boxes.rot, strict=True)
    deepest = [penetration(centre, half, rot, others).max(initial=-np.inf) for centre, half, rot in parts]
    return float(max(deepest, default=-np.inf))


def boxes_hit(boxes: Boxes, others: Boxes, tolerance: float) -> bool:
    """Whether any of `boxes` penetrates any of `others` deeper than `tolerance`."""
    parts = zip(boxes.centre, boxes.half, boxes.rot, strict=True)
    return any(np.any(penetration(centre, half, rot, others) > tolerance) for centre, half, rot in parts)


def depth_across(boxes: Boxes, others: Boxes) -> float:
    """How far `boxes` reach horizontally into `others` (<= 0 when apart), whatever their heights:
    a flat object's overlap in height says nothing of how far it runs into another."""
    return depth(Boxes(boxes.centre, boxes.half + np.array([0.0, 0.0, 1.0]), boxes.rot), others)
