"""Hinged parts: turning a knob, swinging a door shut."""

from __future__ import annotations

import math

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.control import CLOSE, OPEN
from langgap.policies.oracle.geometry import hand_yaw, rotation_about, sweeping_yaw, top_down, wrap_half_turn
from langgap.policies.oracle.grasps import APPROACHES
from langgap.policies.oracle.motion import Agent, Program, actuate, back_off, move, reorient, travel
from langgap.policies.oracle.placement import flight_path
from langgap.policies.oracle.scene import Articulation

DOOR_PUSH_AT = 0.75  # fraction of a door's width from its hinge where it is pushed


def turn(agent: Agent, fixture: str, state: str) -> Program:
    """Turn a knob (a hinge about a vertical axis) into the qpos interval of `state`."""
    art = agent.scene.articulation(fixture)
    top = art.bbox[5]
    grasp_point = np.array([art.anchor[0], art.anchor[1], top - 0.015])
    knob = art.boxes.aabb()
    grip_slab = knob[knob[:, 5] > top - 0.02]
    extent = grip_slab[:, 3:5].max(axis=0) - grip_slab[:, :2].min(axis=0)
    # Close across the knob's narrow side.
    yaw = 0.0 if extent[0] < extent[1] else math.pi / 2
    yaw = wrap_half_turn(yaw, hand_yaw(agent.scene.eef_mat))
    above = grasp_point + np.array([0.0, 0.0, APPROACHES[0]])
    yield from reorient(agent, top_down(yaw), toward=above)
    path = flight_path(agent.scene, agent.scene.eef_pos, above, hang=hand.TIP, reach=hand.REACH)
    yield from travel(agent, above, path=path, rot=top_down(yaw), grip=OPEN, tol=0.01)
    yield from move(agent, grasp_point, tol=0.004, steps=40, speed=0.4)
    yield from actuate(agent, CLOSE)
    goal = art.target(state)
    spin = float(np.sign(art.axis[2]))
    for _ in range(40):
        art = agent.scene.articulation(fixture)
        if art.reached(state):
            break
        step = float(np.clip(goal - art.qpos, -0.4, 0.4)) * spin
        rot = rotation_about(np.array([0.0, 0.0, 1.0]), step) @ agent.scene.eef_mat
        yield agent.command(grasp_point, rot=rot)
    yield from actuate(agent, OPEN)
    yield from back_off(agent)
    return agent.scene.articulation(fixture).holds(state)


def _door_contact(art: Articulation, sense: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Where to push a hinged door: a point on its face trailing the motion, the motion's direction, mid-height."""
    boxes = art.boxes
    centres = boxes.centre[:, :2] - art.anchor[:2]
    arm = centres.mean(axis=0)
    arm /= np.linalg.norm(arm)
    length = float(np.max(centres @ arm))  # to the farthest part's centre
    radius = arm * length * DOOR_PUSH_AT
    tangent = np.cross([0.0, 0.0, sense], [radius[0], radius[1], 0.0])[:2]
    tangent /= np.linalg.norm(tangent)
    # The door's face on the trailing side, near the push point (the main slab, not a handle at its end).
    along = centres @ arm
    spread = np.sum(np.abs(np.einsum("nji,j->ni", boxes.rot, [arm[0], arm[1], 0.0])) * boxes.half, axis=1)
    near = np.abs(along - length * DOOR_PUSH_AT) <= spread
    local = np.abs(np.einsum("nji,j->ni", boxes.rot[near], [tangent[0], tangent[1], 0.0]))
    trailing = np.min(centres[near] @ tangent - np.sum(local * boxes.half[near], axis=1))
    point = art.anchor[:2] + radius + tangent * (trailing - radius @ tangent)
    height = float((boxes.aabb()[:, 2].min() + boxes.aabb()[:, 5].max()) / 2.0)
    return point, tangent, height


def close_door(agent: Agent, fixture: str) -> Program:
    """Swing a hinged door shut by pushing its face, from the side it moves away from, around the hinge."""
    art = agent.scene.articulation(fixture)
    goal = art.target("close")
    sense = float(np.sign(goal - art.qpos) * np.sign(art.axis[2]))
    point, tangent, height = _door_contact(art, sense)
    standoff = hand.FINGER_DEPTH + 0.015
    start = np.array([*(point - tangent * standoff), height])
    # The hand turns with the door all the way shut: of its two equivalent yaws, the one whose wrist
    # has room for that whole turn (the other stalls the arm on its way in).
    sweep = (goal - art.qpos) * art.axis[2]
    yaw = sweeping_yaw(math.atan2(tangent[1], tangent[0]) + math.pi / 2, agent.scene.azimuth(start), sweep)
    yield from actuate(agent, CLOSE, max_steps=8)
    yield from reorient(agent, top_down(yaw), toward=start)
    path = flight_path(agent.scene, agent.scene.eef_pos, start + np.array([0.0, 0.0, 0.05]), hang=hand.TIP, reach=0.05)
    yield from travel(agent, start, path=path, rot=top_down(yaw), grip=CLOSE, tol=0.012)
    for _ in range(100):
        art = agent.scene.articulation(fixture)
        if art.reached("close"):
            break
        point, tangent, _ = _door_contact(art, sense)
        # Stay on the door's face and push along its motion; turn the hand with the door.
        aim = np.array([*(point - tangent * (standoff - 0.03)), height])
        yaw = wrap_half_turn(math.atan2(tangent[1], tangent[0]) + math.pi / 2, hand_yaw(agent.scene.eef_mat))
        yield agent.command(aim, rot=top_down(yaw), speed=0.6)
    yield from back_off(agent)
    return agent.scene.articulation(fixture).holds("close")
