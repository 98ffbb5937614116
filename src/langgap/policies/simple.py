"""Trivial reference policies: `noop` (holds still), `random` (uniform actions, seeded per episode) and
`delay` (holds still at a fixed cost per query, for measuring scheduling and batching)."""

from __future__ import annotations

import time

import numpy as np

from langgap.policies.base import PolicySpec, TaskContext
from langgap.sim.env import Observation


class NoopPolicy:
    """Sends zero motion with the gripper open: the floor every success rate is compared with."""

    spec = PolicySpec(reads_instruction=False)

    def reset(self, context: TaskContext) -> None:
        pass

    def act(self, observation: Observation) -> np.ndarray:
        return np.array([0, 0, 0, 0, 0, 0, -1], dtype=np.float64)


class RandomPolicy:
    """Uniform random actions in [-scale, scale] (gripper ±1), reproducible from the episode seed."""

    def __init__(self, scale: float = 1.0, chunk: int = 1):
        self.scale = scale
        self.spec = PolicySpec(chunk=chunk, replan=chunk, reads_instruction=False)
        self._rng = np.random.default_rng(0)

    def config(self) -> dict:
        return {"scale": self.scale}

    def reset(self, context: TaskContext) -> None:
        self._rng = np.random.default_rng([context.seed, context.init_index])

    def act(self, observation: Observation) -> np.ndarray:
        actions = self._rng.uniform(-self.scale, self.scale, size=(self.spec.chunk, 7))
        actions[:, 6] = np.sign(actions[:, 6]) + (actions[:, 6] == 0)
        return actions


class DelayPolicy(NoopPolicy):
    """Holds still, but each query costs `delay_ms` — per call, however many episodes a batched call serves.

    Stands in for a model whose inference cost is per forward pass, to measure scheduling and batching.
    """

    def __init__(self, delay_ms: float = 50.0):
        self.delay_ms = delay_ms

    def config(self) -> dict:
        return {"delay_ms": self.delay_ms}

    def act(self, observation: Observation) -> np.ndarray:
        time.sleep(self.delay_ms / 1000)
        return super().act(observation)

    @staticmethod
    def act_batch(policies: list[DelayPolicy], observations: list[Observation]) -> list[np.ndarray]:
        time.sleep(policies[0].delay_ms / 1000)
        return [NoopPolicy.act(p, o) for p, o in zip(policies, observations, strict=True)]
