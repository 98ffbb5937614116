"""LIBERO's goal predicates re-stated on a privileged scene, to order and verify sub-goals.

They mirror `libero.libero.envs` (object origins against region boxes, 3 cm for object-on-object)
closely enough to decide what is left to do; the simulator's own check stays the judge of success.
"""

from __future__ import annotations

import numpy as np

from langgap.bddl import Predicate
from langgap.policies.oracle.scene import Region, Scene

ON_OBJECT_RADIUS = 0.03  # LIBERO: origins within 3 cm in xy
UNDER_HEIGHT = 0.10  # LIBERO: an object counts as on a region up to 10 cm above its top face
IN_FLOOR_SLACK = 0.01  # LIBERO: a region box extends 1 cm further down for `In`


def region_box(region: Region, *, inside: bool) -> tuple[np.ndarray, np.ndarray]:
    """World-axis bounds (lo, hi) of where an object's origin satisfies `In` (inside) or `On` a region."""
    half = np.abs(region.mat @ region.size) if inside else np.abs(region.mat.T @ region.size)
    lo, hi = region.pos - half, region.pos + half
    if inside:
        lo[2] -= IN_FLOOR_SLACK
    else:
        lo[2], hi[2] = region.pos[2] + half[2] - 0.005, region.pos[2] + half[2] + UNDER_HEIGHT
    return lo, hi


def region_frame_points(region: Region, *, inside: bool, margin: float, steps: int) -> np.ndarray:
    """A grid of world points (n, 3) whose xy satisfy the region's test with `margin` to spare."""
    if inside:
        half = np.abs(region.mat @ region.size)
        xs = np.linspace(-1, 1, steps) * max(half[0] - margin, 0.0)
        ys = np.linspace(-1, 1, steps) * max(half[1] - margin, 0.0)
        return np.array([region.pos + np.array([x, y, 0.0]) for x in xs for y in ys])
    # LIBERO's `under` test works in the site frame: delta = mat @ (p - pos) within the half-sizes.
    xs = np.linspace(-1, 1, steps) * max(region.size[0] - margin, 0.0)
    ys = np.linspace(-1, 1, steps) * max(region.size[1] - margin, 0.0)
    return np.array([region.pos + region.mat.T @ np.array([x, y, 0.0]) for x in xs for y in ys])


def in_region(scene: Scene, obj: str, region_name: str) -> bool:
    region = scene.region(region_name)
    lo, hi = region_box(region, inside=True)
    return bool(np.all(scene.pos(obj) > lo) and np.all(scene.pos(obj) < hi))


def on_region(scene: Scene, obj: str, region_name: str) -> bool:
    region = scene.region(region_name)
    delta = region.mat @ (scene.pos(obj) - region.pos)
    size = region.size
    return bool(
        size[2] - 0.005 < delta[2] < size[2] + UNDER_HEIGHT
        and np.all(np.abs(delta[:2]) < size[:2])
        and scene.touches_other(obj)
    )


def on_object(scene: Scene, obj: str, target: str) -> bool:
    below, above = scene.pos(target), scene.pos(obj)
    return bool(
        below[2] <= above[2]
        and np.linalg.norm(above[:2] - below[:2]) < ON_OBJECT_RADIUS
        and scene.touches_other(obj)
        and not scene.touches_gripper(obj)
    )


def holds(scene: Scene, predicate: Predicate) -> bool:
    """Whether `predicate` (approximately) holds in `scene`. `Moved` counts as not reached: the oracle aims at
    named places only (the choices `goals.plans` gives it), and the simulator judges `Moved` (`sim.resting`)."""
    name, args = predicate.name, predicate.args
    if not predicate.libero:
        return False
    if name == "On":
        obj, target = args
        return on_object(scene, obj, target) if scene.has_entity(target) else on_region(scene, obj, target)
    if name == "In":
        return in_region(scene, *args)
    state = {"Open": "open", "Close": "close", "Turnon": "on", "Turnoff": "off"}[name]
    return scene.articulation(args[0]).holds(state)
