"""Motion primitives as generators: each yields one action per step and returns whether it got there.

A program is a generator that yields 7-D actions; before it is resumed, `Agent.scene` holds the
newest observation. Primitives compose with `yield from`, so a skill reads as a script.
"""

from __future__ import annotations

from collections.abc import Generator

import numpy as np

from langgap.policies.oracle.control import OPEN, servo
from langgap.policies.oracle.geometry import START_YAW, mat_to_axis_angle, top_down
from langgap.policies.oracle.scene import Scene
from langgap.policies.oracle.skills import DrawerSkill

Program = Generator[np.ndarray, None, bool]

POSITION_TOLERANCE = 0.008
ROTATION_TOLERANCE = 0.08  # radians
PASS_TOLERANCE = 0.025  # for waypoints the hand only passes through
GRIPPER_STILL = 5e-4  # finger travel per step below which the gripper has finished moving
MAX_STEP = 0.05  # the controller's largest position step (one unit of action)
GAIN = 1.5  # the controller covers about 2/3 of a commanded step: aiming further settles sooner
INTEGRAL_ZONE = 0.02
INTEGRAL_GAIN = 0.3
MAX_BIAS = 0.03
STALL_STEPS = 10
STALL_PROGRESS = 0.002
RETREAT = 0.08  # how far the hand lifts after letting go
LARGE_TURN = 0.8  # radians; larger reorientations are done near the base
TURNING_REACH = 0.55  # horizontal distance from the base where the arm turns freely
START_ROT = top_down(START_YAW)  # the hand's orientation when an episode starts


class Agent:
    """What a running program shares: the newest scene, the commanded orientation and gripper, and the
    way it opens drawers."""

    def __init__(self, drawer: DrawerSkill | None = None) -> None:
        self.drawer = drawer or DrawerSkill()
        self.scene: Scene | None = None
        self.rot = START_ROT
        self.grip = OPEN
        self.steps = 0

    def command(self, pos: np.ndarray, rot: np.ndarray | None = None, grip: float | None = None, speed: float = 1.0):
        """One servo action toward `pos` (and `rot`/`grip`, which stay commanded until changed)."""
        if rot is not None:
            self.rot = rot
        if grip is not None:
            self.grip = grip
        return servo(self.scene.eef_pos, self.scene.eef_mat, pos, self.rot, self.grip, speed)

    def rotation_error(self) -> float:
        return float(np.linalg.norm(mat_to_axis_angle(self.rot @ self.scene.eef_mat.T)))


def stalled(history: list[float], steps: int = STALL_STEPS, progress: float = STALL_PROGRESS) -> bool:
    """Whether a distance still to go, logged once a step, shrank by less than `progress` over the
    last `steps` steps."""
    return len(history) > steps and history[-steps - 1] - history[-1] < progress


def move(
    agent: Agent,
    pos: np.ndarray,
    *,
    rot: np.ndarray | None = None,
    grip: float | None = None,
    tol: float = POSITION_TOLERANCE,
    steps: int = 80,
    speed: float = 1.0,
    through: bool = False,
    level: bool = False,
) -> Program:
    """Servo to `pos` until within `tol` (and the orientation within ROTATION_TOLERANCE).

    `through` marks a waypoint the hand only passes: it keeps full speed instead of slowing down,
    and does not wait there for the hand to finish turning.
    Near the target an integral term removes the controller's steady-state offset (a few mm when
    the arm is stretched). `level` keeps the hand at its height on the way too: the integral acts
    on the vertical error from the start (a hand sliding out level sags below its aim, more than a
    centimetre with the arm stretched and the hand horizontal).
    """
    target = np.asarray(pos, dtype=np.float64)
    if rot is not None:
        agent.rot = rot
    bias = np.zeros(3)
    history: list[float] = []
    for _ in range(steps):
        error = target - agent.scene.eef_pos
        distance = float(np.linalg.norm(error))
        if distance < tol and (through or agent.rotation_error() < ROTATION_TOLERANCE):
            return True
        history.append(distance + agent.rotation_error() * 0.05)
        if stalled(history):
            return False  # blocked (an obstacle, the arm's reach): let the caller decide
        if through:
            # Aimed far enough that the largest component saturates: full speed along the line.
            aim = agent.scene.eef_pos + error * max(1.0, MAX_STEP / max(float(np.abs(error).max()), 1e-9))
        else:
            if distance < INTEGRAL_ZONE:
                bias = np.clip(bias + INTEGRAL_GAIN * error, -MAX_BIAS, MAX_BIAS)
            elif level:
                bias[2] = np.clip(bias[2] + INTEGRAL_GAIN * error[2], -MAX_BIAS, MAX_BIAS)
            aim = agent.scene.eef_pos + GAIN * error + bias
        yield agent.command(aim, grip=grip, speed=speed)
    return False


def actuate(agent: Agent, grip: float, *, min_steps: int = 5, max_steps: int = 11) -> Program:
    """Open or close the gripper in place until the fingers stop moving."""
    hold = agent.scene.eef_pos.copy()
    last = None
    for step in range(max_steps):
        width = agent.scene.gripper_width
        if step >= min_steps and last is not None and abs(width - last) < GRIPPER_STILL:
            return True
        last = width
        yield agent.command(hold, grip=grip)
    return True


def travel(
    agent: Agent,
    pos: np.ndarray,
    *,
    path: np.ndarray | None = None,
    rot: np.ndarray | None = None,
    grip: float | None = None,
    tol: float = POSITION_TOLERANCE,
    speed: float = 1.0,
) -> Program:
    """Go to `pos` through the waypoints `path` (n, 3) without stopping at them, then settle on `pos`.

    `speed` (0..1] caps every step, e.g. to carry a load gently. The hand turns to `rot` on its way.
    """
    for waypoint in [] if path is None else path:
        yield from move(agent, waypoint, rot=rot, grip=grip, tol=PASS_TOLERANCE, steps=60, speed=speed, through=True)
    return (yield from move(agent, pos, rot=rot, grip=grip, tol=tol, speed=speed))


def reorient(agent: Agent, rot: np.ndarray, toward: np.ndarray | None = None) -> Program:
    """Start turning the hand to `rot` for a motion toward `toward`; the motion that follows finishes the turn.

    The servo commands position and orientation together, so a hand turns on its way. A large turn
    with the arm stretched out, though, can straighten the elbow against its limit, where the
    controller no longer moves the hand: such a turn begins while the hand is drawn in to
    TURNING_REACH from the base (in the direction of `toward`, else of the hand), where the arm has
    room to turn.
    """
    turn = float(np.linalg.norm(mat_to_axis_angle(rot @ agent.scene.eef_mat.T)))
    here = agent.scene.eef_pos
    if turn < LARGE_TURN or agent.scene.reach(here) <= TURNING_REACH:
        return True
    outward = (here if toward is None else np.asarray(toward))[:2] - agent.scene.base_pos[:2]
    inward = agent.scene.base_pos[:2] + outward / np.linalg.norm(outward) * TURNING_REACH
    staging = np.array([*inward, here[2] + 0.03])
    return (yield from move(agent, staging, rot=rot, tol=PASS_TOLERANCE, steps=30, through=True))


def back_off(agent: Agent, away: np.ndarray | None = None) -> Program:
    """Lift the hand clear (and move it by `away`) after letting go of something."""
    lift = np.array([0.0, 0.0, RETREAT]) + (np.zeros(3) if away is None else away)
    return (yield from move(agent, agent.scene.eef_pos + lift, tol=0.02, steps=20))


def hold(agent: Agent) -> Program:
    """Stay where the hand is, forever (the program's end)."""
    here = agent.scene.eef_pos.copy()
    while True:
        yield agent.command(here)
