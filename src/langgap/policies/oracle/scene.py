"""A read-only view of one privileged observation (its keys: `langgap.sim.privileged_schema`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from langgap.policies.oracle.geometry import Boxes, quat_to_mat
from langgap.sim.privileged_schema import articulation_names, names

INTERVAL_MARGIN = 0.15


@dataclass(frozen=True)
class Articulation:
    """One articulated part (a drawer, a door, a knob) as the privileged state describes it."""

    qpos: float
    anchor: np.ndarray
    axis: np.ndarray
    slide: bool
    limits: np.ndarray
    bbox: np.ndarray
    handle: np.ndarray
    intervals: dict[str, np.ndarray]
    boxes: Boxes  # collision boxes of the moving part

    def target(self, state: str) -> float:
        """A qpos safely inside the interval where `state` (open, close, on, off) holds.

        It is the interval's boundary nearest the other states, moved 15 % into the interval: far
        enough to hold after release, no further than needed (an opened drawer sticks out less).
        """
        lo, hi = self.intervals[state]
        others = [v.mean() for k, v in self.intervals.items() if k != state]
        if not others:
            return float((lo + hi) / 2.0)
        reference = float(np.mean(others))
        inner = lo if abs(lo - reference) < abs(hi - reference) else hi
        return float(inner + (hi + lo - 2 * inner) * INTERVAL_MARGIN)

    def reached(self, state: str) -> bool:
        """Whether the joint is at or beyond `target(state)`, well inside the interval of `state`."""
        lo, hi = self.intervals[state]
        target = self.target(state)
        inward = np.sign((lo + hi) / 2.0 - target) or 1.0
        return bool(self.holds(state) and (self.qpos - target) * inward >= 0.0)

    def holds(self, state: str) -> bool:
        """Whether the joint is in the interval of `state` (open-ended where it reaches a joint limit,
        since a joint pressed against its limit may overshoot it slightly)."""
        lo, hi = self.intervals[state]
        lo = -np.inf if lo <= self.limits[0] + 1e-9 else lo
        hi = np.inf if hi >= self.limits[1] - 1e-9 else hi
        return bool(lo <= self.qpos <= hi)


@dataclass(frozen=True)
class Region:
    """A region site: frame and the half-sizes LIBERO's `In`/`On` checks use."""

    name: str
    pos: np.ndarray
    mat: np.ndarray
    size: np.ndarray


class Scene:
    """Typed accessors over a privileged dict; raises KeyError for names the scene lacks."""

    def __init__(self, privileged: Mapping[str, np.ndarray]):
        self.raw = privileged
        self.eef_pos = np.asarray(privileged["eef_pos"], dtype=np.float64)
        self.eef_mat = np.asarray(privileged["eef_mat"], dtype=np.float64)
        self.gripper_width = float(np.sum(np.abs(privileged["gripper_qpos"])))
        self.base_pos = np.asarray(privileged["base_pos"], dtype=np.float64)
        self.entities = names(privileged, "body/")
        self.regions = names(privileged, "site/")
        self.articulated = articulation_names(privileged)

    def reach(self, point: np.ndarray) -> float:
        """Horizontal distance from the robot's base to `point`."""
        return float(np.linalg.norm(np.asarray(point)[:2] - self.base_pos[:2]))

    def azimuth(self, point: np.ndarray) -> float:
        """Direction of `point` seen from the robot's base (radians, horizontal)."""
        x, y = np.asarray(point)[:2] - self.base_pos[:2]
        return math.atan2(y, x)

    def has_entity(self, name: str) -> bool:
        return f"body/{name}" in self.raw

    def has_region(self, name: str) -> bool:
        return f"site/{name}" in self.raw

    def pos(self, name: str) -> np.ndarray:
        return np.asarray(self.raw[f"body/{name}"][:3], dtype=np.float64)

    def rot(self, name: str) -> np.ndarray:
        return quat_to_mat(self.raw[f"body/{name}"][3:7])

    def bbox(self, name: str) -> np.ndarray:
        return np.asarray(self.raw[f"bbox/{name}"], dtype=np.float64)

    def shape(self, name: str) -> np.ndarray:
        """Collision boxes of `name` in its body frame (n, 6)."""
        return np.asarray(self.raw[f"shape/{name}"], dtype=np.float64).reshape(-1, 6)

    def boxes(self, name: str) -> Boxes:
        """Collision boxes of `name` at its current pose (each geom's bounds in the body's frame:
        conservative where a geom is turned in it)."""
        return Boxes.from_local(self.shape(name), self.rot(name), self.pos(name))

    def parts(self, name: str) -> Boxes:
        """The collision geoms of `name` as oriented boxes at its current pose (tight: a plate's slanted
        rim leaves its middle free, where `boxes` fill it)."""
        local = np.asarray(self.raw[f"parts/{name}"], dtype=np.float64).reshape(-1, 15)
        body = self.rot(name)
        rot = np.einsum("ij,njk->nik", body, local[:, 6:].reshape(-1, 3, 3))
        return Boxes(local[:, :3] @ body.T + self.pos(name), local[:, 3:6], rot)

    def movable(self, name: str) -> bool:
        """A loose object (True) or a fixture (False)."""
        return bool(self.raw[f"movable/{name}"][0] > 0.5)

    def touches_other(self, name: str) -> bool:
        """Whether `name` touches anything except itself and the robot."""
        return bool(self.raw[f"contact/{name}"][0] > 0.5)

    def touches_gripper(self, name: str) -> bool:
        return bool(self.raw[f"contact/{name}"][1] > 0.5)

    def region(self, name: str) -> Region:
        return Region(
            name=name,
            pos=np.asarray(self.raw[f"site/{name}"], dtype=np.float64),
            mat=np.asarray(self.raw[f"site_mat/{name}"], dtype=np.float64).reshape(3, 3),
            size=np.asarray(self.raw[f"site_size/{name}"], dtype=np.float64),
        )

    def articulation(self, name: str) -> Articulation:
        prefix = f"art/{name}/"
        body = self.raw[prefix + "body"]
        shape = np.asarray(self.raw[prefix + "shape"], dtype=np.float64).reshape(-1, 6)
        return Articulation(
            qpos=float(self.raw[prefix + "qpos"][0]),
            anchor=np.asarray(self.raw[prefix + "anchor"], dtype=np.float64),
            axis=np.asarray(self.raw[prefix + "axis"], dtype=np.float64),
            slide=bool(self.raw[prefix + "slide"][0] > 0.5),
            limits=np.asarray(self.raw[prefix + "limits"], dtype=np.float64),
            bbox=np.asarray(self.raw[prefix + "bbox"], dtype=np.float64),
            handle=np.asarray(self.raw[prefix + "handle"], dtype=np.float64),
            intervals={
                key: np.asarray(self.raw[prefix + key], dtype=np.float64)
                for key in ("open", "close", "on", "off")
                if prefix + key in self.raw
            },
            boxes=Boxes.from_local(shape, quat_to_mat(body[3:7]), np.asarray(body[:3], dtype=np.float64)),
        )

    def with_part_moved(self, name: str, offset: np.ndarray) -> Scene:
        """The scene as it would be with the moving part of articulation `name` shifted by `offset`
        (e.g. a drawer pulled open), to ask before acting what the hand could do then."""
        raw = dict(self.raw)
        body = self.raw[f"art/{name}/body"]
        shift = np.asarray(offset, dtype=np.float64)
        for other in self.articulated:  # the same part is also listed under its fixture's name
            prefix = f"art/{other}/"
            if np.array_equal(self.raw[prefix + "body"], body):
                raw[prefix + "body"] = np.concatenate([body[:3] + shift, body[3:]])
                raw[prefix + "bbox"] = self.raw[prefix + "bbox"] + np.tile(shift, 2)
                raw[prefix + "handle"] = self.raw[prefix + "handle"] + shift
        return Scene(raw)

    def loose(self, exclude: tuple[str, ...] = ()) -> tuple[str, ...]:
        """The loose (movable) objects, but those of `exclude`."""
        return tuple(e for e in self.entities if e not in exclude and self.movable(e))

    def loose_boxes(self, exclude: tuple[str, ...] = ()) -> Boxes:
        """Collision boxes of the loose objects, but those of `exclude`."""
        return Boxes.concat([self.boxes(e) for e in self.loose(exclude)])

    def obstacles(self, exclude: tuple[str, ...] = (), *, fixtures_only: bool = False) -> Boxes:
        """Collision boxes of every entity and moving part except those of `exclude` (names or their parts)."""
        parts = [self.boxes(e) for e in self.entities if e not in exclude and not (fixtures_only and self.movable(e))]
        # Every articulated part once: a fixture's first joint is also listed under the fixture's name.
        seen: dict[bytes, Boxes] = {}
        excluded: set[bytes] = set()
        for name in self.articulated:
            boxes = self.articulation(name).boxes
            key = boxes.centre.tobytes()
            seen[key] = boxes
            if any(name == e or name.startswith(e + "_") for e in exclude):
                excluded.add(key)
        parts += [boxes for key, boxes in seen.items() if key not in excluded]
        return Boxes.concat(parts)
