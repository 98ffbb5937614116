"""The `small-bc` policy: a checkpoint trained by `langgap train small-bc`, acting on simulator state.

It reads the instruction as text (word tokens through the model's learned embeddings) and the
scene from `observation.privileged` (entity poses, proprioception: its spec `sees_state`); it is
never told the task id or the goal (its spec does not declare `sees_goal`), so it is a policy under
test that reads simulator state, not a scripted reference. Inference runs on one CPU thread, deterministically.
"""

from __future__ import annotations

import numpy as np

from langgap.policies.base import PolicySpec, TaskContext, regressed_chunk, simulator_state
from langgap.policies.learned import LearnedPolicy
from langgap.sim.env import Observation


class SmallBCPolicy(LearnedPolicy):
    """`--policy-arg checkpoint=PATH` (required); `replan=k` executes the first k actions of each chunk."""

    def __init__(self, checkpoint: str = "", replan: int = 2):
        from langgap.policies.small_bc.model import load_checkpoint

        super().__init__(checkpoint, kind="small-bc", load=load_checkpoint)
        chunk = self.model.config.chunk
        # It reads the simulator state but is never told the goal: a learned policy under test.
        self.spec = PolicySpec(sees_state=True, chunk=chunk, replan=min(replan, chunk))
        self._names: list[str] | None = None
        self._name_ids = None

    def reset(self, context: TaskContext) -> None:
        super().reset(context)
        self._names = None

    def act(self, observation: Observation) -> np.ndarray:
        from langgap.policies.small_bc import features

        torch = self._torch
        privileged = simulator_state(observation, "small-bc")
        instruction = self.instruction_ids(observation)
        if self._names is None:
            self._names = features.entity_names(privileged)
            width = self.model.config.max_name_words
            self._name_ids = torch.tensor(
                [[self.vocab.encode(features.name_words(n), width) for n in self._names]], dtype=torch.int64
            )
        with torch.inference_mode():
            actions = self.model(
                torch.from_numpy(features.proprio(privileged))[None],
                torch.from_numpy(features.entities(privileged, self._names))[None],
                self._name_ids,
                instruction,
            )[0].numpy()
        return regressed_chunk(actions)
