"""Where to put an object down: a spot on another object or inside a region, and how high to fly."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.geometry import Boxes, bounds_xy, boxes_hit
from langgap.policies.oracle.predicates import region_box, region_frame_points
from langgap.policies.oracle.scene import Scene

CLEARANCE = 0.03  # above the tallest obstacle when flying
EDGE_MARGIN = 0.012  # keep the object's origin this far inside a region
GRID = 9  # candidate spots per region side
LIFT_GAP = 0.004  # a candidate footprint is tested this far above the support
PATH_SPACING = 0.05
BLOCKED_COST = 10.0  # per loose object in the way of a spot
ASIDE_DISTANCES = (0.12, 0.16, 0.2, 0.25)
ASIDE_DIRECTIONS = 12
ASIDE_MAX_REACH = 0.72
ASIDE_MARGIN = 0.015  # room around a load put aside: held, it may tilt and grow its bounding box
WRIST_HEIGHT = 0.2  # the hand and wrist rise this far above the grip site
ESCAPE_DISTANCES = (0.05, 0.08, 0.12)
HAND_HALF_WIDTH = 0.03
LOAD_MARGIN = 0.02  # a carried load passes obstacles this far apart (it swings a little in the fingers)


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


@dataclass(frozen=True)
class RegionSpot(Spot):
    """A spot in a region, and the loose objects in its way (empty when it is free)."""

    blockers: tuple[str, ...] = ()


def spots_in_region(scene: Scene, obj: str, region_name: str, *, inside: bool) -> list[RegionSpot]:
    """Spots for `obj` inside region `region_name` (`inside`: LIBERO's `In`, else `On`/under), best first.

    The object rests on the region's own surface (a fixture's, not another object's: `On` needs
    the contact). The best spot is clear of everything and central; its `blockers` name the loose
    objects in the way when no spot is clear. After the best come the others nearest the robot
    first (easiest to reach into, e.g. the front of a microwave).
    """
    region = scene.region(region_name)
    fixed = scene.obstacles(exclude=(obj,), fixtures_only=True)
    loose = scene.loose(exclude=(obj,))
    everything = scene.obstacles(exclude=(obj,))
    lo, hi = region_box(region, inside=inside)
    scored = []
    for point in region_frame_points(region, inside=inside, margin=EDGE_MARGIN, steps=GRID):
        support = support_height(fixed, point[:2], hi[2])
        support = max(lo[2] + 0.01, region.pos[2]) if support is None else support
        placed = footprint_at(scene, obj, point[:2], support + LIFT_GAP)
        if boxes_hit(placed, fixed, 0.001):
            continue
        blockers = tuple(e for e in loose if boxes_hit(placed, scene.boxes(e), 0.001))
        spread = float(np.linalg.norm(point[:2] - region.pos[:2]))
        cost = BLOCKED_COST * len(blockers) + spread
        cost -= 0.5 * _nearest_free_distance(placed.aabb(), everything.aabb(), support)
        scored.append((cost, RegionSpot(xy=point[:2], support=support, blockers=blockers)))
    if not scored:
        return [RegionSpot(xy=region.pos[:2], support=float(region.pos[2]))]
    scored.sort(key=lambda item: item[0])
    best = scored[0][1]
    free = [spot for cost, spot in scored[1:] if len(spot.blockers) <= len(best.blockers)]
    return [best] + sorted(free, key=lambda spot: scene.reach(spot.xy))


def spots_aside(scene: Scene, obj: str, keep_clear: np.ndarray, then: np.ndarray | None = None) -> list[Spot]:
    """Free spots on the table near `obj` but outside the box `keep_clear` (lo xyz, hi xyz), best first.

    The best is the one with the shortest flight there (one beside a tall fixture needs a climb
    over it) and, with `then` (where the hand goes next), on from there; several are offered so
    that the grasp can be chosen for a spot where the hand, too, fits (not against a fixture).
    """
    everything = scene.obstacles(exclude=(obj,))
    table = min(scene.bbox(e)[2] for e in scene.loose())
    here = scene.pos(obj)[:2]
    bounds = scene.bbox(obj)
    box = bounds + np.array([-ASIDE_MARGIN, -ASIDE_MARGIN, 0.0, ASIDE_MARGIN, ASIDE_MARGIN, 0.0])
    height = float(box[5] - box[2])
    start = np.array([*here, box[5]])
    extent = bounds_xy(bounds, here)
    scored = []
    for distance in ASIDE_DISTANCES:
        for k in range(ASIDE_DIRECTIONS):
            angle = 2 * np.pi * k / ASIDE_DIRECTIONS
            xy = here + distance * np.array([np.cos(angle), np.sin(angle)])
            # The object's bounding box, as the carrying hand's collision checks see the load (with
            # room for it tilting in the fingers).
            shift = np.array([*(xy - here), table + LIFT_GAP - box[2]])
            placed = Boxes.from_local((box + np.tile(shift, 2))[None, :], np.eye(3), np.zeros(3))
            low, high = placed.aabb()[0, :2], placed.aabb()[0, 3:5]
            inside = bool(np.all(high > keep_clear[:2]) and np.all(low < keep_clear[3:5]))
            if inside or boxes_hit(placed, everything, 0.001) or scene.reach(xy) > ASIDE_MAX_REACH:
                continue
            end = np.array([*xy, table + height])
            path = flight_path(scene, start, end, exclude=(obj,), hang=height, reach=LOAD_MARGIN, extent=extent)
            length = np.sum(np.linalg.norm(np.diff(np.vstack([start, path]), axis=0), axis=1)) + path[-1][2] - end[2]
            if then is not None:
                length += float(np.linalg.norm(then[:2] - xy))
            scored.append((float(length), scene.reach(xy), Spot(xy=xy, support=table)))
    return [spot for *_, spot in sorted(scored, key=lambda item: item[:2])]


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
    extent: np.ndarray | None = None,
    footprint: np.ndarray | None = None,
) -> np.ndarray:
    """Waypoints (n, 3) from `start` to above `end` that keep a load clear of every obstacle.

    `hang` is how far the load (or the fingers) reaches below the grip site, `reach` how far it
    reaches sideways beyond `extent` (x/y lo, x/y hi around the path's points: what the hand carries,
    as the hand holds it; a point when None; given, the palm and wrist above the load are kept clear
    too, by their own height); `footprint` (x/y lo, x/y hi) is its extent at the start. The path
    slides out from under anything overhanging the load, rises, flies at the height each stretch
    needs and ends straight above `end`, so the last move is a vertical descent.
    """
    obstacles = scene.obstacles(exclude=exclude).aabb()
    length = float(np.linalg.norm(end[:2] - start[:2]))
    count = max(2, int(length / PATH_SPACING) + 1)
    samples = start[None, :2] + np.linspace(0.0, 1.0, count)[:, None] * (end[:2] - start[:2])[None, :]
    loaded = extent is not None
    own = _tops_near(obstacles, samples, extent if loaded else np.zeros(4), reach, beside_start=loaded)
    own += hang + CLEARANCE
    if loaded:
        # The palm and wrist above a load may reach beyond it, but they only need to clear their own height.
        palm = _tops_near(obstacles, samples, np.zeros(4), hand.PALM_HALF_LENGTH, beside_start=True)
        own = np.maximum(own, palm + hand.PALM + CLEARANCE)
    # Between two samples the load passes near what either sample is near: take the larger need.
    needed = own.copy()
    needed[1:] = np.maximum(needed[1:], own[:-1])
    needed[:-1] = np.maximum(needed[:-1], own[1:])
    # In free space the height changes linearly from the start's to the end's.
    base = start[2] + np.linspace(0.0, 1.0, count) * (end[2] - start[2])
    heights = np.maximum(needed, base)
    # Rise straight above the start to the first stretch's height, then cross: a diagonal first stretch
    # drags a load lifted beside a fixture (an open drawer's underside) sideways into it while it climbs.
    heights[0] = max(start[2], heights[1])
    # No dips between two higher stretches: rise once, cross, descend once.
    heights = np.minimum(np.maximum.accumulate(heights), np.maximum.accumulate(heights[::-1])[::-1])
    path = [np.array([*samples[0], heights[0]])]
    path += [np.array([*xy, z]) for xy, z in zip(samples[1:], heights[1:], strict=True)]
    if footprint is None:
        footprint = np.concatenate([start[:2] - HAND_HALF_WIDTH, start[:2] + HAND_HALF_WIDTH])
    escape = _escape(obstacles, start, footprint, float(heights.max()), hang)
    return np.array(([escape] if escape is not None else []) + path)


def _tops_near(
    obstacles: np.ndarray, samples: np.ndarray, extent: np.ndarray, reach: float, *, beside_start: bool = False
) -> np.ndarray:
    """Per sample (x, y), the highest top of the obstacles within `reach` of the rectangle `extent` around it.

    With `beside_start` (a load held as it will be carried), the samples run along a straight path
    from the first: an obstacle the rectangle stands beside at the start (near, not over it) is left out
    where the path is no nearer to it than there, since the load already stands at its height that
    close (a bowl lifted from beside a cabinet need not fly over it). An empty hand turns on its way,
    which sweeps its fingers out of where they stood: not for it.
    """
    low, high = samples[:, None, :] + extent[:2], samples[:, None, :] + extent[2:]
    apart = np.maximum(np.maximum(obstacles[None, :, :2] - high, low - obstacles[None, :, 3:5]), 0.0)
    gap = np.linalg.norm(apart, axis=2)
    near = gap <= reach
    if beside_start:
        near &= ~((gap[0] > 0.0) & (gap >= gap[0]))
    return np.where(near, obstacles[None, :, 5], -np.inf).max(axis=1)


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
