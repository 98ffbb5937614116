"""The privileged observation's schema: the simulator state shown to a policy whose spec `sees_state`.

A `PrivilegedState` is a read-only mapping from flat string keys to numpy arrays, so it crosses a
process or network boundary as a plain map (`arrays`), and it is checked against this schema when it
is built, wherever that happens (the environment, a policy server receiving it, a test): an unknown
key, a missing one or a wrong shape fails with a `PrivilegedStateError` that names the key.

Keys (`<e>` = an object or fixture of the scene, `<s>` = a region site, `<a>` = an articulated
entity: a fixture with joints or a region site bound to joints); `n` is any length:

* robot: `eef_pos` (3), `eef_mat` (3, 3): the end-effector site `gripper0_grip_site`;
  `gripper_qpos` (2); `base_pos` (3): the robot's base (how far the arm must reach).
* entity `<e>`: `body/<e>` (7): position + wxyz quaternion of its root body; `bbox/<e>` (6, only for
  an entity with collision geoms): world-frame axis-aligned box (min xyz, max xyz) of its collision
  geoms; `movable/<e>` (1): 1.0 for a loose object, 0.0 for a fixture; `shape/<e>` (n, 6): its
  collision geoms as boxes in its root body's frame, for fixtures only the parts no joint moves
  (static); `parts/<e>` (n, 15): the same geoms as oriented boxes in that frame: centre (3),
  half-sizes along the box's own axes (3), rotation into the body's frame (9, row-major; static);
  `contact/<e>` (2): whether it touches something other than itself and the robot, and whether it
  touches the gripper (1.0 / 0.0).
* site `<s>`: `site/<s>` (3), `site_mat/<s>` (3, 3), `site_size/<s>` (3): a region site's frame and
  the half-sizes LIBERO's `In`/`On` checks use.
* `joint/<name>` (1): qpos of each articulated fixture joint.
* articulation `<a>` (its first joint): `art/<a>/qpos` (1), `art/<a>/anchor` (3), `art/<a>/axis` (3),
  `art/<a>/slide` (1: 1 slide, 0 hinge), `art/<a>/limits` (2); `art/<a>/body` (7): pose of the body
  that joint moves; `art/<a>/shape` (n, 6): its collision geoms as boxes in that body's frame
  (static); with collision geoms, `art/<a>/bbox` (6): their world box and `art/<a>/handle` (3):
  centre of the moving part that reaches furthest along the opening direction; and where the
  fixture defines LIBERO's predicate of that name, `art/<a>/open|close|on|off` (2): the qpos
  interval, within the joint limits, where it holds.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

import numpy as np

# A shape; None: any length along that axis.
Shape = tuple[int | None, ...]

ROBOT: dict[str, Shape] = {"eef_pos": (3,), "eef_mat": (3, 3), "gripper_qpos": (2,), "base_pos": (3,)}


@dataclass(frozen=True)
class Family:
    """Keys describing one named thing: `<field>/<name>` (or `art/<name>/<field>`), required and optional fields."""

    what: str
    required: dict[str, Shape]
    optional: dict[str, Shape] = field(default_factory=dict)

    def shape(self, member: str) -> Shape | None:
        return self.required.get(member, self.optional.get(member))


ENTITY = Family(
    "entity",
    {"body": (7,), "movable": (1,), "shape": (None, 6), "parts": (None, 15), "contact": (2,)},
    {"bbox": (6,)},
)
SITE = Family("site", {"site": (3,), "site_mat": (3, 3), "site_size": (3,)})
JOINT = Family("joint", {"joint": (1,)})
ARTICULATION = Family(
    "articulation",
    {"qpos": (1,), "anchor": (3,), "axis": (3,), "slide": (1,), "limits": (2,), "body": (7,), "shape": (None, 6)},
    {"bbox": (6,), "handle": (3,), "open": (2,), "close": (2,), "on": (2,), "off": (2,)},
)
# The first part of a `<field>/<name>` key -> its family.
_BY_PREFIX = {member: family for family in (ENTITY, SITE, JOINT) for member in family.required | family.optional}


class PrivilegedStateError(ValueError):
    """A privileged state does not follow the schema (a key unknown, missing or of the wrong shape)."""


def _split(key: str) -> tuple[Family, str, str]:
    """The family, the thing's name and the field a key names; `PrivilegedStateError` for an unknown key."""
    if key.startswith("art/"):
        name, _, member = key[4:].rpartition("/")
        if name and ARTICULATION.shape(member) is not None:
            return ARTICULATION, name, member
    else:
        member, _, name = key.partition("/")
        if name and member in _BY_PREFIX:
            return _BY_PREFIX[member], name, member
    raise PrivilegedStateError(f"privileged state: unknown key {key!r} (see langgap.sim.privileged_schema)")


def _key(family: Family, name: str, member: str) -> str:
    return f"art/{name}/{member}" if family is ARTICULATION else f"{member}/{name}"


@functools.lru_cache(maxsize=64)
def _layout(keys: tuple[str, ...]) -> tuple[Shape, ...]:
    """The expected shape of each of `keys`, once the set is known to be complete (cached: every step
    of an episode has the same keys, so a step's check is one shape comparison per key)."""
    shapes: list[Shape] = []
    seen: dict[tuple[str, str], tuple[Family, set[str]]] = {}  # (family, name) -> the family, the fields present
    for key in keys:
        if not isinstance(key, str):
            raise PrivilegedStateError(f"privileged state: key {key!r} is not a string")
        if key in ROBOT:
            shapes.append(ROBOT[key])
            continue
        family, name, member = _split(key)
        shapes.append(family.shape(member))
        seen.setdefault((family.what, name), (family, set()))[1].add(member)
    missing = [key for key in ROBOT if key not in keys]
    for (_, name), (family, present) in seen.items():
        missing += [_key(family, name, member) for member in family.required.keys() - present]
    if missing:
        raise PrivilegedStateError(f"privileged state: missing {', '.join(repr(k) for k in sorted(missing))}")
    return tuple(shapes)


def _fits(shape: tuple[int, ...], expected: Shape) -> bool:
    return len(shape) == len(expected) and all(e is None or e == n for n, e in zip(shape, expected, strict=True))


def validated(arrays: Mapping[str, object]) -> dict[str, np.ndarray]:
    """`arrays` as numeric numpy arrays, checked against the schema (`PrivilegedStateError` otherwise)."""
    out = {key: np.asarray(value) for key, value in arrays.items()}
    for (key, value), expected in zip(out.items(), _layout(tuple(out)), strict=True):
        if value.dtype.kind not in "fiub":
            raise PrivilegedStateError(f"privileged state: {key!r} is not numeric (dtype {value.dtype})")
        if not _fits(value.shape, expected):
            wanted = str(tuple("n" if e is None else e for e in expected)).replace("'", "")
            raise PrivilegedStateError(f"privileged state: {key!r} has shape {value.shape}, expected {wanted}")
    return out


@dataclass(frozen=True, eq=False)
class PrivilegedState(Mapping[str, np.ndarray]):
    """The simulator state at one step, validated against the schema (module docstring); read-only.

    Read it as a mapping (`state["eef_pos"]`, `state[f"body/{name}"]`); `arrays` is the plain dict
    that travels over a wire.
    """

    arrays: Mapping[str, np.ndarray]

    def __post_init__(self) -> None:
        object.__setattr__(self, "arrays", validated(self.arrays))

    def __getitem__(self, key: str) -> np.ndarray:
        return self.arrays[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.arrays)

    def __len__(self) -> int:
        return len(self.arrays)


def names(state: Mapping[str, object], prefix: str) -> tuple[str, ...]:
    """The names of the things whose key starts with `prefix` (`body/`, `site/`, `joint/`), in key order."""
    return tuple(key[len(prefix) :] for key in state if key.startswith(prefix))


def articulation_names(state: Mapping[str, object]) -> tuple[str, ...]:
    """The articulated entities of a state, in key order."""
    return tuple(key[4:-5] for key in state if key.startswith("art/") and key.endswith("/qpos"))
