"""The `small-vla` policy: a checkpoint trained by `langgap train small-vla`, acting on what a VLA sees.

It is shown both cameras at the checkpoint's image size, the 8-D state and the instruction, nothing else: its
spec declares neither `sees_state` nor `sees_goal`, so it is a policy under test with exactly a VLA's inputs.
Inference runs on one CPU thread, deterministically.
"""

from __future__ import annotations

import numpy as np

from langgap.policies.base import PolicySpec, regressed_chunk
from langgap.policies.learned import LearnedPolicy
from langgap.sim.env import CAMERAS, Observation


class SmallVLAPolicy(LearnedPolicy):
    """`--policy-arg checkpoint=PATH` (required); `replan=k` executes the first k actions of each chunk."""

    def __init__(self, checkpoint: str = "", replan: int = 4):
        from langgap.policies.small_vla.model import load_checkpoint

        super().__init__(checkpoint, kind="small-vla", load=load_checkpoint)
        config = self.model.config
        self.spec = PolicySpec(
            cameras=CAMERAS, image_size=config.image_size, chunk=config.chunk, replan=min(replan, config.chunk)
        )

    def act(self, observation: Observation) -> np.ndarray:
        torch = self._torch
        instruction = self.instruction_ids(observation)
        images = np.stack([observation.images[camera] for camera in CAMERAS])[None]
        with torch.inference_mode():
            actions = self.model(torch.from_numpy(images), torch.from_numpy(observation.state)[None], instruction)
        return regressed_chunk(actions[0].numpy())
