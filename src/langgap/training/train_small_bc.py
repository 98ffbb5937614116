"""Training `small-bc` by behaviour cloning on collected demonstrations (CPU).

Every frame of every selected demonstration is a sample: its observation, its instruction, and the
next `chunk` actions (the loss ignores steps past the demonstration's end). Deterministic for a given
seed and thread count.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from langgap.demos.compact import load_demos
from langgap.demos.record import Demo
from langgap.policies.chunk_transformer import save_checkpoint
from langgap.policies.small_bc import features
from langgap.policies.small_bc.model import ModelConfig, Normalizer, SmallBC
from langgap.policies.text import Vocabulary
from langgap.training.loop import TrainConfig, chunk_loss, chunk_targets, optimise, selected, training_facts

__all__ = ["TrainConfig", "train"]


@dataclass
class Samples:
    """All frames as arrays (N = frames, E = max entities, W = name words, L = instruction words)."""

    proprio: np.ndarray  # (N, 14)
    entities: np.ndarray  # (N, E, 11)
    names: np.ndarray  # (N, E, W) word ids
    instruction: np.ndarray  # (N, L) word ids
    actions: np.ndarray  # (N, chunk, 7)
    action_mask: np.ndarray  # (N, chunk)


def training_texts(demos: list[Demo]) -> list[str]:
    """The sentences and entity names of `demos`: the vocabulary of a `vocabulary: training` run."""
    names = {features.name_words(n) for d in demos for n in features.entity_names(d.privileged)}
    return [d.instruction for d in demos] + sorted(names)


def build_samples(demos: list[Demo], vocab: Vocabulary, config: ModelConfig) -> Samples:
    """Turn demonstrations into training arrays."""
    max_entities = max(len(features.entity_names(d.privileged)) for d in demos)
    parts: dict[str, list[np.ndarray]] = {k: [] for k in Samples.__dataclass_fields__}
    for demo in demos:
        n = demo.length
        names = features.entity_names(demo.privileged)
        ents = np.zeros((n, max_entities, features.ENTITY_DIM), dtype=np.float32)
        ents[:, : len(names)] = features.entities(demo.privileged, names)
        name_ids = np.zeros((max_entities, config.max_name_words), dtype=np.int64)
        for i, name in enumerate(names):
            name_ids[i] = vocab.encode(features.name_words(name), config.max_name_words)
        targets, mask = chunk_targets(demo.labels, config.chunk)
        parts["proprio"].append(features.proprio(demo.privileged))
        parts["entities"].append(ents)
        parts["names"].append(np.broadcast_to(name_ids, (n, *name_ids.shape)))
        parts["instruction"].append(np.tile(vocab.encode(demo.instruction, config.max_words), (n, 1)))
        parts["actions"].append(targets)
        parts["action_mask"].append(mask)
    return Samples(**{k: np.concatenate(v) for k, v in parts.items()})


def select_demos(config: TrainConfig, log=print) -> list[Demo]:
    """The demonstrations of `config.tasks` (all if None; see `langgap.training.loop.selected`)."""
    return selected(config, load_demos([Path(p) for p in config.data]), log)


def train(config: TrainConfig, out: str | Path, *, log_every: int = 200, log=print) -> dict:
    """Train a small-bc model on `config`'s demonstrations and save it to `out`; returns training facts."""
    started = time.perf_counter()
    device = config.seeded_device()
    model_config = config.model or ModelConfig()
    demos = select_demos(config, log)
    vocab = config.words(training_texts(demos))
    samples = build_samples(demos, vocab, model_config)
    tensors = {k: torch.from_numpy(np.ascontiguousarray(v)).to(device) for k, v in asdict(samples).items()}
    normalizer = Normalizer.fit(samples.proprio, samples.entities, samples.names[..., 0] > 0)
    model = SmallBC(model_config, len(vocab), normalizer).to(device)
    frames = len(samples.proprio)

    def loss_of(batch: torch.Tensor) -> torch.Tensor:
        predicted = model(
            tensors["proprio"][batch],
            tensors["entities"][batch],
            tensors["names"][batch],
            tensors["instruction"][batch],
        )
        return chunk_loss(predicted, tensors["actions"][batch], tensors["action_mask"][batch], config.loss)

    loss_value = optimise(model, loss_of, frames, config, log_every=log_every, log=log)
    facts = training_facts(config, demos, frames, loss_value, started)
    save_checkpoint(out, model.cpu(), vocab, facts)
    return facts
