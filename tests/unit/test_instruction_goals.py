"""A reference policy's goal follows its instruction: the privileged context names each instruction's goal,
and it crosses the openpi wire intact."""

from __future__ import annotations

import numpy as np

from langgap.policies import protocol
from langgap.policies.base import PrivilegedContext, TaskContext, current_instruction
from langgap.sim.env import Observation


def _context() -> TaskContext:
    privileged = PrivilegedContext(
        task_id="spatial/s0/b",
        condition="switch:20",
        goal=("(On b plate)",),
        source_goal=("(On a plate)",),
        goal_expression="(On b plate)",
        instruction_goals=(("put a on the plate", "(On a plate)"),),
    )
    return TaskContext("put a on the plate", "libero_spatial", 0, 0, 220, privileged)


def test_the_goal_of_each_instruction():
    privileged = _context().privileged
    assert privileged.goal_for("put a on the plate") == "(On a plate)"
    assert privileged.goal_for("put b on the plate") == "(On b plate)"  # the task's own under any other


def test_the_instruction_in_force_is_the_observation_s_else_the_context_s():
    context = _context()
    assert current_instruction(Observation(state=np.zeros(8)), context) == "put a on the plate"
    assert current_instruction(Observation(state=np.zeros(8), instruction=""), context) == ""
    assert current_instruction(Observation(state=np.zeros(8), instruction="put b"), context) == "put b"


def test_the_context_crosses_the_wire_with_its_instruction_goals():
    context = _context()
    message = protocol.unpack(protocol.pack({"context": protocol.context_to_message(context)}))["context"]
    assert protocol.context_from_message(message) == context
