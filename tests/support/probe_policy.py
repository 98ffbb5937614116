"""A policy whose actions depend on everything it observes (served as `tests.support.probe_policy:ProbePolicy`)."""

from __future__ import annotations

import numpy as np

from langgap.policies.base import PolicySpec, TaskContext
from langgap.sim.env import CAMERAS, Observation


class ProbePolicy:
    """Actions computed from everything it observes, so a served copy matches in process only if every
    image pixel, the state, the simulator state and the context arrive intact."""

    spec = PolicySpec(cameras=CAMERAS, image_size=64, sees_state=True, sees_goal=True, chunk=4, replan=2)

    def reset(self, context: TaskContext) -> None:
        text = sum(map(ord, context.instruction)) % 1000
        self._offset = text / 1000.0 + context.seed * 1e-3 + len(context.privileged.goal) * 1e-2

    def act(self, observation: Observation) -> np.ndarray:
        features = [observation.state.astype(np.float64).sum()]
        features += [observation.images[c].astype(np.float64).mean() / 255.0 for c in CAMERAS]
        features += [float(np.asarray(v, dtype=np.float64).sum()) for _, v in sorted(observation.privileged.items())]
        phase = np.arange(4)[:, None] + np.arange(7)[None, :] + sum(features) + self._offset
        actions = 0.5 * np.sin(phase)
        actions[:, 6] = np.where(actions[:, 6] > 0, 1.0, -1.0)
        return actions
