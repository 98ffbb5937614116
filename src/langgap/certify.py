"""Reachability of a drawer's handle: can any gripper pose that holds the bar be reached without collision?

A task the scripted oracle cannot do may still be doable. For a drawer, the question the simulator
can answer is whether the robot can hold the handle at all: every pose in which the Panda's pads
close across the bar (the approach turned around the bar from below-front to above-behind, the
grip anywhere along the bar and up to a pad's half-height off its centre, both wrist flips) is
solved for with inverse kinematics within the arm's joint limits (damped least squares from the
arm's start configuration and random ones), and the hand and fingers are checked against the
fixed scene (table, cabinet, other fixtures) at that pose. Loose objects do not count: they can be
moved first. Where the hand itself intersects a fixture, no arm configuration helps — the hand's
pose is the grasp's — so the smallest such intersection over the whole family is a bound a reviewer
can check: if it exceeds the tolerance, no pose that holds the handle is reachable.

Runs on one init state (fixtures do not move between init states).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from langgap import goals
from langgap.bddl import Predicate
from langgap.catalog.task import Task
from langgap.errors import LangGapError
from langgap.policies.oracle.hand import FINGER_THICKNESS

TOLERANCE_M = 0.002  # contact deeper than this is a collision (MuJoCo's soft contacts overlap slightly)
ANGLES_DEG = tuple(range(-30, 121, 5))  # approach around the bar: 0 from the front, 90 from above
ALONG_FRACTIONS = (-0.6, -0.3, 0.0, 0.3, 0.6)  # grip points along the bar, as fractions of its half-length
DEPTHS_M = (-0.008, 0.0, 0.008)  # grip offsets along the approach (the pads still cover the bar)
RANDOM_SEEDS = 8
IK_ITERATIONS = 300
IK_POSITION_M = 0.002
IK_ROTATION_RAD = 0.02
_ROBOT = ("robot0_", "gripper0_", "mount0_")
_HAND = "gripper0_"


@dataclass(frozen=True)
class PoseResult:
    """One grasp pose of the family."""

    angle_deg: int
    along_m: float
    depth_m: float
    flip: int
    reachable: bool  # inverse kinematics found joint angles within the limits
    hand_penetration_m: float  # deepest intersection of the hand or fingers with a fixture (nan: unreachable)
    arm_penetration_m: float  # deepest of the arm's links, best configuration found (nan: unreachable)
    worst_contact: str  # the fixture geom the hand meets deepest

    @property
    def clear(self) -> bool:
        """Reachable, and neither the hand nor the arm meets a fixture beyond the tolerance."""
        return self.reachable and self.hand_penetration_m <= TOLERANCE_M and self.arm_penetration_m <= TOLERANCE_M


@dataclass(frozen=True)
class HandleReach:
    """The whole family of poses for one drawer, and what it shows."""

    task_id: str
    init_index: int
    handle: tuple[float, float, float]
    poses: list[PoseResult]
    family: str  # the poses tried, in words
    hook_gap_m: float = math.inf  # room between the handle bar and the drawer's face, for a finger hooking it

    @property
    def reachable(self) -> list[PoseResult]:
        return [p for p in self.poses if p.reachable]

    @property
    def clear(self) -> list[PoseResult]:
        """Reachable poses whose hand and arm meet no fixture beyond the tolerance."""
        return [p for p in self.poses if p.clear]

    @property
    def certified(self) -> bool:
        """True when no pose that holds the handle can be reached without the hand meeting a fixture,
        and no finger fits between the bar and the drawer's face to hook it."""
        blocked = not self.clear and all(p.hand_penetration_m > TOLERANCE_M for p in self.reachable)
        return blocked and self.hook_gap_m < FINGER_THICKNESS

    def certificate(self) -> str:
        """The evidence in one paragraph (empty when the family has a clear pose)."""
        if not self.certified:
            return ""
        closest = min(self.reachable, key=lambda p: p.hand_penetration_m, default=None)
        where = (
            f"the least-colliding one (approach {closest.angle_deg}° around the bar, {1000 * closest.along_m:+.0f} mm "
            f"along it) still puts the hand {1000 * closest.hand_penetration_m:.0f} mm into "
            f"{closest.worst_contact}"
            if closest
            else "none is within the arm's joint limits"
        )
        return (
            f"Reachability on init state {self.init_index}: of {len(self.poses)} gripper poses that hold the handle "
            f"bar at {tuple(round(v, 3) for v in self.handle)} (pads closing across it; {self.family}; "
            f"both wrist flips), inverse kinematics within the arm's joint limits reaches {len(self.reachable)} "
            f"(none found for the other {len(self.poses) - len(self.reachable)} from {RANDOM_SEEDS + 1} starting "
            f"configurations), and in every one the hand or fingers intersect a fixed part of the scene by more "
            f"than {1000 * TOLERANCE_M:.0f} mm; {where}. Nor can a finger hook the bar: the gap between the bar and "
            f"the drawer's face is {1000 * self.hook_gap_m:.0f} mm, the finger's thinnest section "
            f"{1000 * FINGER_THICKNESS:.0f} mm."
        )


def _grasp_frames(direction: np.ndarray, bar: np.ndarray, angle: float) -> list[np.ndarray]:
    """Grip-site frames (x: closing axis, z: approach) with the pads closing across a horizontal bar."""
    approach = math.cos(angle) * -direction - math.sin(angle) * np.array([0.0, 0.0, 1.0])
    frames = []
    for flip in (1.0, -1.0):
        y = flip * bar
        x = np.cross(y, approach)
        frames.append(np.stack([x, y, approach], axis=1))
    return frames


class _Robot:
    """The arm and hand of one environment, for inverse kinematics and collision queries."""

    def __init__(self, env):
        import mujoco

        self.mujoco = mujoco
        self.model = env.sim.model._model
        self.start = env.sim.data._data
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "gripper0_grip_site")
        joints = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"robot0_joint{i}") for i in range(1, 8)]
        self.qpos = np.array([m.jnt_qposadr[j] for j in joints])
        self.dofs = np.array([m.jnt_dofadr[j] for j in joints])
        self.low, self.high = m.jnt_range[joints, 0], m.jnt_range[joints, 1]
        fingers = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"gripper0_finger_joint{i}") for i in (1, 2)]
        self.fingers = np.array([m.jnt_qposadr[j] for j in fingers])
        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or "" for b in range(m.nbody)]
        self.robot_body = np.array([n.startswith(_ROBOT) for n in names])
        self.hand_body = np.array([n.startswith(_HAND) for n in names])

    def solve(self, pos: np.ndarray, rot: np.ndarray, seed: np.ndarray) -> np.ndarray | None:
        """Joint angles within the limits that put the grip site at (pos, rot), or None."""
        m, d, mujoco = self.model, self.data, self.mujoco
        d.qpos[:] = self.start.qpos
        d.qpos[self.qpos] = seed
        jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        for _ in range(IK_ITERATIONS):
            mujoco.mj_kinematics(m, d)
            mujoco.mj_comPos(m, d)
            current = d.site_xmat[self.site].reshape(3, 3)
            position_error = pos - d.site_xpos[self.site]
            rotation_error = 0.5 * sum(np.cross(current[:, k], rot[:, k]) for k in range(3))
            if np.linalg.norm(position_error) < IK_POSITION_M and np.linalg.norm(rotation_error) < IK_ROTATION_RAD:
                return d.qpos[self.qpos].copy()
            mujoco.mj_jacSite(m, d, jacp, jacr, self.site)
            jac = np.vstack([jacp[:, self.dofs], jacr[:, self.dofs]])
            step = jac.T @ np.linalg.solve(
                jac @ jac.T + 1e-3 * np.eye(6), np.concatenate([position_error, rotation_error])
            )
            d.qpos[self.qpos] = np.clip(d.qpos[self.qpos] + np.clip(step, -0.2, 0.2), self.low, self.high)
        return None

    def penetration(self, q: np.ndarray, opening: float, loose: tuple[str, ...]) -> tuple[float, float, str]:
        """(hand, arm) deepest intersection with fixtures at joint angles `q`, fingers `opening` apart."""
        m, d, mujoco = self.model, self.data, self.mujoco
        d.qpos[:] = self.start.qpos
        d.qpos[self.qpos] = q
        d.qpos[self.fingers] = (opening / 2, -opening / 2)
        mujoco.mj_forward(m, d)
        hand, arm, worst = 0.0, 0.0, ""
        for contact in d.contact[: d.ncon]:
            bodies = m.geom_bodyid[[contact.geom1, contact.geom2]]
            robot = self.robot_body[bodies]
            if robot[0] == robot[1]:
                continue
            other = contact.geom2 if robot[0] else contact.geom1
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, other) or f"geom {other}"
            if name.startswith(loose):
                continue
            depth = -contact.dist
            if self.hand_body[bodies[0] if robot[0] else bodies[1]]:
                if depth > hand:
                    hand, worst = depth, name
            else:
                arm = max(arm, depth)
        return hand, arm, worst


def required_opening(goal: goals.Goal) -> Predicate | None:
    """The one `Open` that every way of meeting `goal` needs (a drawer task, or an ordering with it),
    or None when there is none or more than one: only then is the drawer's reachability the task's."""
    needed: set[Predicate] | None = None
    for plan in goals.plans(goal):
        opened = {p for stage in plan for p in stage if p.name == "Open"}
        needed = opened if needed is None else needed & opened
    return next(iter(needed)) if needed is not None and len(needed) == 1 else None


def sharing(tasks: Iterable[Task], task: Task) -> list[Task]:
    """The tasks of `tasks` a certificate for `task` holds for: those needing the same drawer opened on
    the same source's scene. The analysis reads the fixtures and the robot of the source's init state
    (one t0 state per source and init state, a claim the gate checks), so it is the same for each."""
    opening = required_opening(task.goal)
    if opening is None:
        return []
    return [t for t in tasks if t.source == task.source and required_opening(t.goal) == opening]


def handle_reach(
    task: Task,
    init_index: int = 0,
    *,
    angles: tuple[int, ...] = ANGLES_DEG,
    along: tuple[float, ...] = ALONG_FRACTIONS,
    depths: tuple[float, ...] = DEPTHS_M,
) -> HandleReach:
    """Try every gripper pose that holds the handle of the drawer `task`'s goal opens (see the module);
    a smaller family (`angles`, `along`, `depths`) answers faster but certifies only itself."""
    from langgap.policies.oracle.drawers import drawer_front, opening_direction
    from langgap.policies.oracle.hand import PAD_HALF_HEIGHT
    from langgap.policies.oracle.scene import Scene
    from langgap.sim.env import EnvOptions, TaskEnv
    from langgap.sim.privileged import privileged_state

    opening = required_opening(task.goal)
    if opening is None:
        raise LangGapError(
            f"certify analyses tasks whose goal needs one drawer opened; {task.id}'s goal is "
            f"{' '.join(task.goal_strings)}"
        )
    with TaskEnv(task, EnvOptions(privileged=True)) as env:
        env.reset(init_index)
        env.settle()
        scene = Scene(privileged_state(env))
        region = opening.args[0]
        art = scene.articulation(region)
        direction = opening_direction(art)
        _, bar, half_length = drawer_front(art, direction)
        loose = scene.loose()
        robot = _Robot(env)
        rng = np.random.default_rng(0)
        seeds = [robot.start.qpos[robot.qpos].copy()] + [
            rng.uniform(robot.low, robot.high) for _ in range(RANDOM_SEEDS)
        ]
        opening = 2 * (PAD_HALF_HEIGHT + 0.002)  # the pads just clear the bar
        poses = []
        for angle in angles:
            for flip, rot in enumerate(_grasp_frames(direction, bar, math.radians(angle))):
                for fraction in along:
                    for depth in depths:
                        pos = art.handle + fraction * half_length * bar + depth * rot[:, 2]
                        found = []
                        for seed in seeds:
                            q = robot.solve(pos, rot, seed)
                            if q is not None:
                                found.append(robot.penetration(q, opening, loose))
                                if found[-1][1] <= TOLERANCE_M:
                                    break
                        if found:
                            hand, arm, worst = min(found, key=lambda f: (f[0], f[1]))
                            result = PoseResult(angle, fraction * half_length, depth, flip, True, hand, arm, worst)
                        else:
                            result = PoseResult(
                                angle, fraction * half_length, depth, flip, False, math.nan, math.nan, ""
                            )
                        poses.append(result)
    family = f"{len(angles)} approach angles from {angles[0]}° to {angles[-1]}° around the bar"
    family += f", {len(along)} grip points along it"
    family += f", {len(depths)} depths"
    gap = hook_gap(art, direction)
    return HandleReach(task.id, init_index, tuple(float(v) for v in art.handle), poses, family, gap)


def hook_gap(art, direction: np.ndarray) -> float:
    """The room between a drawer's handle bar and its face (the front panel, not the bar's posts),
    along the opening direction."""
    from langgap.policies.oracle.drawers import handle_parts

    boxes = art.boxes
    reach, bar = handle_parts(art, direction)
    back = float(np.max(boxes.centre[bar] @ direction - boxes.extent(direction)[bar]))
    width = boxes.extent(np.cross([0.0, 0.0, 1.0], direction))
    panels = ~bar & (width >= float(np.max(width[bar])))  # as wide as the bar: not its posts
    return back - float(np.max(reach[panels]))
