"""The `oracle` and `blind` policies: a scripted planner over privileged state, through the normal action interface."""

from __future__ import annotations

import numpy as np

from langgap.policies.base import PolicySpec, PrivilegedContext, TaskContext, simulator_state
from langgap.policies.oracle.motion import Agent, Program
from langgap.policies.oracle.planner import OracleError, parse_goal, program
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
    """

    spec = PolicySpec(sees_state=True, sees_goal=True)

    def __init__(self, noise: float = 0.0, noise_seed: int = 0, drawer: str = "auto"):
        if noise < 0:
            raise OracleError(f"noise must be >= 0, got {noise}")
        self.noise = noise
        self.noise_seed = noise_seed
        self.drawer = DrawerSkill.parse(drawer)
        self._goal: tuple = ()
        self._agent = Agent(self.drawer)
        self._program: Program | None = None
        self._rng = np.random.default_rng(0)

    def config(self) -> dict:
        config: dict = {"noise": self.noise}
        # Only where they differ from the defaults: stored runs of the plain oracle keep their config hash.
        if self.noise_seed:
            config["noise_seed"] = self.noise_seed
        if self.drawer != DrawerSkill():
            config["drawer"] = str(self.drawer)
        return config

    def goal_of(self, context: PrivilegedContext) -> tuple[str, ...]:
        """The goal this policy pursues: the task's own expression, with any order and negation it states."""
        return (context.goal_expression,)

    def reset(self, context: TaskContext) -> None:
        if context.privileged is None:
            raise OracleError("the oracle needs the privileged context (the task's goal: PolicySpec.sees_goal)")
        self._goal = parse_goal(self.goal_of(context.privileged))
        self._agent = Agent(self.drawer)
        self._program = None
        noise_key = [context.seed, context.init_index] + ([self.noise_seed] if self.noise_seed else [])
        self._rng = np.random.default_rng(noise_key)

    def act(self, observation: Observation) -> np.ndarray:
        self._agent.scene = Scene(simulator_state(observation, "the oracle"))
        if self._program is None:
            self._program = program(self._agent, self._goal)
        action = next(self._program)
        if self.noise > 0:
            action = action.copy()
            action[:6] = np.clip(action[:6] + self._rng.normal(0.0, self.noise, size=6), -1.0, 1.0)
        return action


class BlindPolicy(OraclePolicy):
    """The oracle run on the source task's goal whatever the instruction says: a policy that memorised the scene."""

    def goal_of(self, context: PrivilegedContext) -> tuple[str, ...]:
        return context.source_goal
