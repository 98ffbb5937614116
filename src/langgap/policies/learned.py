"""What LangGap's own learned policies (`small-bc`, `small-vla`) share as policies: a checkpoint loaded once,
inference on one CPU thread, and the instruction in force encoded as word ids (again only when it changes)."""

from __future__ import annotations

from collections.abc import Callable

from langgap.policies.base import TaskContext, current_instruction
from langgap.policies.checkpoints import CheckpointArgumentError
from langgap.sim.env import Observation


class LearnedPolicy:
    """A policy whose model, vocabulary and training facts come from the checkpoint `load` reads."""

    def __init__(self, checkpoint: str, *, kind: str, load: Callable[[str], tuple]):
        if not checkpoint:
            raise CheckpointArgumentError(
                "{kind} needs {checkpoint}=PATH (a file written by `langgap train`)", kind=kind
            )
        import torch

        torch.set_num_threads(1)  # deterministic, and one core per worker
        self.checkpoint = checkpoint
        self._torch = torch
        self.model, self.vocab, self.training = load(checkpoint)
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

    def instruction_ids(self, observation: Observation):
        """The (1, L) word ids of the instruction in force at `observation` (it may change mid-episode)."""
        instruction = current_instruction(observation, self._context)
        if instruction != self._text:
            self._encode(instruction)
        return self._instruction
