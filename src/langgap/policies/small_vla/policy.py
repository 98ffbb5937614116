"""The `small-vla` policy: a checkpoint trained by `langgap train small-vla`, acting on what a VLA sees.

It is shown both cameras at the checkpoint's image size, the 8-D state and the instruction, nothing else: its
spec declares neither `sees_state` nor `sees_goal`, so it is a policy under test with exactly a VLA's inputs.
Inference runs on one CPU thread, deterministically.
"""

from __future__ import annotations

import numpy as np

from langgap.policies.base import PolicySpec, TaskContext, current_instruction, regressed_chunk
from langgap.sim.env import CAMERAS, Observation


class SmallVLAPolicy:
    """`--policy-arg checkpoint=PATH` (required); `replan=k` executes the first k actions of each chunk."""

    def __init__(self, checkpoint: str = "", replan: int = 4):
        from langgap.policies.checkpoints import CheckpointError
        from langgap.policies.small_vla.model import load_checkpoint

        if not checkpoint:
            raise CheckpointError("small-vla needs --policy-arg checkpoint=PATH (a file written by `langgap train`)")
        import torch

        torch.set_num_threads(1)
        self.checkpoint = checkpoint
        self._torch = torch
        self.model, self.vocab, self.training = load_checkpoint(checkpoint)
        config = self.model.config
        self.spec = PolicySpec(
            cameras=CAMERAS, image_size=config.image_size, chunk=config.chunk, replan=min(replan, config.chunk)
        )
        self._context: TaskContext | None = None
        self._text: str | None = None
        self._instruction = None

    def config(self) -> dict:
        return {"checkpoint": self.checkpoint, "training": self.training}

    def reset(self, context: TaskContext) -> None:
        self._context = context
        self._encode(context.instruction)

    def _encode(self, instruction: str) -> None:
        ids = self.vocab.encode(instruction, self.model.config.max_words)
        self._text = instruction
        self._instruction = self._torch.tensor([ids], dtype=self._torch.int64)

    def act(self, observation: Observation) -> np.ndarray:
        torch = self._torch
        instruction = current_instruction(observation, self._context)
        if instruction != self._text:  # the instruction changed mid-episode
            self._encode(instruction)
        images = np.stack([observation.images[camera] for camera in CAMERAS])[None]
        with torch.inference_mode():
            actions = self.model(
                torch.from_numpy(images), torch.from_numpy(observation.state)[None], self._instruction
            )[0].numpy()
        return regressed_chunk(actions)
