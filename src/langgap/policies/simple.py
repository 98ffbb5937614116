"""Trivial reference policies: `noop` (holds still) and `random` (uniform actions, seeded per episode)."""

from __future__ import annotations

import numpy as np

from langgap.policies.base import PolicySpec, TaskContext
from langgap.sim.env import Observation


class NoopPolicy:
    """Sends zero motion with the gripper open: the floor every success rate is compared with."""

    spec = PolicySpec()

    def reset(self, context: TaskContext) -> None:
        pass

    def act(self, observation: Observation) -> np.ndarray:
        return np.array([0, 0, 0, 0, 0, 0, -1], dtype=np.float64)


class RandomPolicy:
    """Uniform random actions in [-scale, scale] (gripper ±1), reproducible from the episode seed."""

    def __init__(self, scale: float = 1.0, chunk: int = 1):
        self.scale = scale
        self.spec = PolicySpec(chunk=chunk, replan=chunk)
        self._rng = np.random.default_rng(0)

    def config(self) -> dict:
        return {"scale": self.scale}

    def reset(self, context: TaskContext) -> None:
        self._rng = np.random.default_rng([context.seed, context.init_index])

    def act(self, observation: Observation) -> np.ndarray:
        actions = self._rng.uniform(-self.scale, self.scale, size=(self.spec.chunk, 7))
        actions[:, 6] = np.sign(actions[:, 6]) + (actions[:, 6] == 0)
        return actions
