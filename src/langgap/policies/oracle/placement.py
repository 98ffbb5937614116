"""Where to put an object down: a spot on another object or inside a region, and how high to fly."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from langgap.policies.oracle.geometry import Boxes, boxes_hit
from langgap.policies.oracle.predicates import region_box, region_frame_points
from langgap.policies.oracle.scene import Scene

CLEARANCE = 0.03  # above the tallest obstacle when flying
EDGE_MARGIN = 0.012  # keep the object's origin this far inside a region
GRID = 9  # candidate spots per region side
LIFT_GAP = 0.004  # a candidate footprint is tested this far above the support
PATH_SPACING = 0.05
WRIST_HEIGHT = 0.2  # the hand and wrist rise this far above the grip site
ESCAPE_DISTANCES = (0.05, 0.08, 0.12)
HAND_HALF_WIDTH = 0.03


@dataclass(frozen=True)
class Spot:
    """Where the object's origin should end up (xy) and the surface height expected under it."""

    xy: np.ndarray
    support: float


def support_height(obstacles: Boxes, xy: np.ndarray, below: float, radius: float = 0.0) -> float | None:
    """The highest box top under `xy` (within `radius`) that is not above `below`; None if none."""
    tops = obstacles.aabb()[:, 5]
    under = obstacles.under(xy, radius) & (tops <= below)
    return float(tops[under].max()) if under.any() else None


def footprint_at(scene: Scene, obj: str, xy: np.ndarray, bottom: float) -> Boxes:
    """The object's boxes moved so its origin is over `xy` and its lowest point at `bottom`."""
    boxes = scene.boxes(obj)
    lowest = boxes.aabb()[:, 2].min()
    return boxes.shifted(np.array([*(xy - scene.pos(obj)[:2]), bottom - lowest]))


def spot_on_object(scene: Scene, obj: str, target: str) -> Spot:
    """On another object: over its origin (LIBERO checks origins within 3 cm), resting on its top."""
    xy = scene.pos(target)[:2]
    boxes = scene.boxes(target)
    support = support_height(boxes, xy, np.inf, radius=0.01)
    return Spot(xy=xy, support=float(boxes.aabb()[:, 5].max()) if support is None else support)


def spot_in_region(scene: Scene, obj: str, region_name: str, *, inside: bool) -> Spot:
    """A free spot for `obj` inside region `region_name` (`inside`: LIBERO's `In`, else `On`/under)."""
    region = scene.region(region_name)
    obstacles = scene.obstacles(exclude=(obj,))
    lo, hi = region_box(region, inside=inside)
    candidates = region_frame_points(region, inside=inside, margin=EDGE_MARGIN, steps=GRID)
    best, best_cost = None, np.inf
    for point in candidates:
        support = support_height(obstacles, point[:2], hi[2])
        support = max(lo[2] + 0.01, region.pos[2]) if support is None else support
        placed = footprint_at(scene, obj, point[:2], support + LIFT_GAP)
        spread = float(np.linalg.norm(point[:2] - region.pos[:2]))
        cost = (100.0 if boxes_hit(placed, obstacles, 0.001) else 0.0) + spread
        cost -= 0.5 * _nearest_free_distance(placed.aabb(), obstacles.aabb(), support)
        if cost < best_cost:
            best, best_cost = Spot(xy=point[:2], support=support), cost
    return best


def _nearest_free_distance(placed: np.ndarray, obstacles: np.ndarray, support: float, cap: float = 0.05) -> float:
    """Horizontal distance from the placed footprint to the nearest obstacle standing above the support."""
    standing = obstacles[obstacles[:, 5] > support + 0.01]
    if len(standing) == 0:
        return cap
    lo, hi = placed[:, :2].min(axis=0), placed[:, 3:5].max(axis=0)
    gap = np.maximum(np.maximum(standing[:, :2] - hi, lo - standing[:, 3:5]), 0.0)
    return float(min(cap, np.linalg.norm(gap, axis=1).min()))


def flight_path(
    scene: Scene,
    start: np.ndarray,
    end: np.ndarray,
    *,
    exclude: tuple[str, ...] = (),
    hang: float = 0.0,
    reach: float = 0.05,
    footprint: np.ndarray | None = None,
) -> np.ndarray:
    """Waypoints (n, 3) from `start` to above `end` that keep a load clear of every obstacle.

    `hang` is how far the load (or the fingers) reaches below the grip site, `reach` how far it
    reaches sideways; `footprint` (x/y lo, x/y hi) is its extent at the start. The path slides out
    from under anything overhanging the load, rises, flies at the height each stretch needs and
    ends straight above `end`, so the last move is a vertical descent.
    """
    obstacles = scene.obstacles(exclude=exclude).aabb()
    length = float(np.linalg.norm(end[:2] - start[:2]))
    count = max(2, int(length / PATH_SPACING) + 1)
    samples = start[None, :2] + np.linspace(0.0, 1.0, count)[:, None] * (end[:2] - start[:2])[None, :]
    gap = np.maximum(
        np.maximum(obstacles[None, :, :2] - samples[:, None, :], samples[:, None, :] - obstacles[None, :, 3:5]), 0.0
    )
    near = np.linalg.norm(gap, axis=2) <= reach
    tops = np.where(near, obstacles[None, :, 5], -np.inf).max(axis=1)
    heights = np.maximum(tops + hang + CLEARANCE, end[2])
    heights[0] = max(heights[0], start[2])
    # No dips between two higher stretches: rise once, cross, descend once.
    heights = np.minimum(np.maximum.accumulate(heights), np.maximum.accumulate(heights[::-1])[::-1])
    path = [np.array([*samples[0], heights[0]])]
    path += [np.array([*xy, z]) for xy, z in zip(samples[1:], heights[1:], strict=True)]
    if footprint is None:
        footprint = np.concatenate([start[:2] - HAND_HALF_WIDTH, start[:2] + HAND_HALF_WIDTH])
    escape = _escape(obstacles, start, footprint, float(heights.max()), hang)
    return np.array(([escape] if escape is not None else []) + path)


def _overhead(obstacles: np.ndarray, footprint: np.ndarray, low: float, high: float) -> bool:
    """Whether any obstacle over the rectangle `footprint` (x/y lo, x/y hi) occupies heights in (low, high)."""
    over = np.all((obstacles[:, :2] < footprint[2:]) & (obstacles[:, 3:5] > footprint[:2]), axis=1)
    return bool(np.any(over & (obstacles[:, 2] < high) & (obstacles[:, 5] > low)))


def _escape(obstacles: np.ndarray, start: np.ndarray, footprint: np.ndarray, cruise: float, hang: float):
    """A point beside `start`, at its height, from which the load can rise: None if it can rise where it is.

    Something may overhang the load (an open drawer above a bowl); then slide out from under it first.
    """
    low, high = start[2] - hang + 0.005, cruise + WRIST_HEIGHT
    if not _overhead(obstacles, footprint, start[2] + 0.01, high):
        return None
    for distance in ESCAPE_DISTANCES:
        for k in range(8):
            shift = distance * np.array([np.cos(2 * np.pi * k / 8), np.sin(2 * np.pi * k / 8)])
            if _overhead(obstacles, footprint + np.tile(shift, 2), start[2] + 0.01, high):
                continue
            steps = np.linspace(0.0, 1.0, 6)[1:]
            if any(_overhead(obstacles, footprint + np.tile(t * shift, 2), low, start[2] + 0.01) for t in steps):
                continue
            return np.array([*(start[:2] + shift), start[2]])
    return None
