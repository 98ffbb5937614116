"""The `oracle` and `blind` policies: a scripted planner over privileged state, through the normal action interface."""

from __future__ import annotations

import numpy as np

from langgap.policies.base import PolicySpec, PrivilegedContext, TaskContext, current_instruction, simulator_state
from langgap.policies.oracle.motion import Agent, Program
from langgap.policies.oracle.planner import OracleError, parse_goal, program, replan
from langgap.policies.oracle.scene import Scene
from langgap.policies.oracle.skills import DrawerSkill
from langgap.sim.env import Observation


class OraclePolicy:
    """Solves a task from its goal (order, negation and alternatives included) and the privileged simulator state.

    It reads the world only from `observation.privileged` and the goal only from the context, and
    answers with the 7-D OSC_POSE delta + gripper action at 20 Hz like any policy. `noise` adds
    Gaussian noise (that standard deviation, in action units) to the six motion components, seeded
    from the episode's seed and init index (and `noise_seed`, for another draw), for diverse
    demonstrations. `drawer` fixes how drawers are opened (`skills.DrawerSkill.parse`).
    It follows its instruction: when the instruction in force changes to one that asks for another goal
    (`PrivilegedContext.goal_for`; condition `switch:K`), it puts down what it holds, closes what it opened
    where the new goal needs it closed (`planner.needs_rest`) and replans from the current state.
    """

    spec = PolicySpec(sees_state=True, sees_goal=True)

    def __init__(self, noise: float = 0.0, noise_seed: int = 0, drawer: str = "auto"):
        if noise < 0:
            raise OracleError(f"noise must be >= 0, got {noise}")
        self.noise = noise
        self.noise_seed = noise_seed
        self.drawer = DrawerSkill.parse(drawer)
        self._goal: tuple = ()
        self._goal_strings: tuple[str, ...] = ()
        self._instruction = ""
        self._context: TaskContext | None = None
        self._agent = Agent(self.drawer)
        self._program: Program | None = None
        self._start: Scene | None = None  # the scene the episode's first action saw
        self._rng = np.random.default_rng(0)

    def config(self) -> dict:
        config: dict = {"noise": self.noise}
        # Only where they differ from the defaults: stored runs of the plain oracle keep their config hash.
        if self.noise_seed:
            config["noise_seed"] = self.noise_seed
        if self.drawer != DrawerSkill():
            config["drawer"] = str(self.drawer)
        return config

    def goal_of(self, context: PrivilegedContext, instruction: str) -> tuple[str, ...]:
        """The goal this policy pursues under `instruction`: the expression it asks for in this episode (the
        task's own, but for a switch's first instruction), with any order and negation it states."""
        return (context.goal_for(instruction),)

    def reset(self, context: TaskContext) -> None:
        if context.privileged is None:
            raise OracleError("the oracle needs the privileged context (the task's goal: PolicySpec.sees_goal)")
        self._context = context
        self._instruction = context.instruction
        self._goal_strings = self.goal_of(context.privileged, context.instruction)
        self._goal = parse_goal(self._goal_strings)
        self._agent = Agent(self.drawer)
        self._program = None
        self._start = None
        noise_key = [context.seed, context.init_index] + ([self.noise_seed] if self.noise_seed else [])
        self._rng = np.random.default_rng(noise_key)

    def act(self, observation: Observation) -> np.ndarray:
        self._agent.scene = Scene(simulator_state(observation, "the oracle"))
        if self._start is None:
            self._start = self._agent.scene
        instruction = current_instruction(observation, self._context)
        if instruction != self._instruction:
            self._instruction = instruction
            goal_strings = self.goal_of(self._context.privileged, instruction)
            if goal_strings != self._goal_strings:  # asked for another goal: replan from where the scene is
                self._goal_strings, self._goal = goal_strings, parse_goal(goal_strings)
                started = self._program is not None
                self._program = replan(self._agent, self._goal, self._start) if started else None
        if self._program is None:
            self._program = program(self._agent, self._goal)
        action = next(self._program)
        if self.noise > 0:
            action = action.copy()
            action[:6] = np.clip(action[:6] + self._rng.normal(0.0, self.noise, size=6), -1.0, 1.0)
        return action


class BlindPolicy(OraclePolicy):
    """The oracle run on the source task's goal whatever the instruction says: a policy that memorised the scene
    (it never follows a switch: it persists by construction). It is told no instruction (`reads_instruction`)."""

    spec = PolicySpec(sees_state=True, sees_goal=True, reads_instruction=False)

    def goal_of(self, context: PrivilegedContext, instruction: str) -> tuple[str, ...]:
        return context.source_goal
