"""Training `small-vla` by behaviour cloning on demonstrations with images (CPU, or a GPU unchanged).

Every frame of every selected demonstration is a sample: both cameras, the 8-D state, the instruction, and the
next `chunk` actions (the loss ignores steps past the demonstration's end). Images are shifted at random by up to
`SHIFT` pixels (edges repeated), a standard regulariser for behaviour cloning from pixels. Deterministic for a given
seed and thread count.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import torch

from langgap.errors import ParameterError
from langgap.policies.chunk_transformer import save_checkpoint
from langgap.policies.small_vla.model import SmallVLA, StateNormalizer, VisionConfig
from langgap.training.image_demos import ImageDemo, load_image_demos
from langgap.training.loop import TrainConfig, chunk_loss, chunk_targets, optimise, selected, training_facts

SHIFT = 4  # pixels, at 96 px (scaled with the image size)


def random_shift(images: torch.Tensor, pad: int, generator: torch.Generator) -> torch.Tensor:
    """(B, C, H, W, 3) uint8 -> the same shape as float, each image moved by up to `pad` pixels each way."""
    batch, cameras, height, width, _ = images.shape
    flat = images.flatten(0, 1).permute(0, 3, 1, 2).float()
    padded = torch.nn.functional.pad(flat, (pad, pad, pad, pad), mode="replicate")
    offsets = torch.randint(2 * pad + 1, (len(flat), 2), generator=generator).tolist()
    shifted = torch.stack([padded[i, :, y : y + height, x : x + width] for i, (y, x) in enumerate(offsets)])
    return shifted.permute(0, 2, 3, 1).reshape(batch, cameras, height, width, 3)


def train(config: TrainConfig, out: str | Path, *, log_every: int = 200, log=print) -> dict:
    """Train a small-vla model on `config`'s demonstrations (their images at the model's size) and save it to
    `out`; returns training facts."""
    started = time.perf_counter()
    device = config.seeded_device()
    loaded = load_image_demos(config.data, config.tasks)
    # The loader read only the selected tasks, so the selection checks and notes; it drops nothing.
    demos: list[ImageDemo] = selected(config, loaded.demos, log)
    size = demos[0].image_size
    model_config = config.model or VisionConfig(image_size=size)
    if model_config.image_size != size:
        raise ParameterError(
            "the model takes {wanted} px images and the demonstrations hold {size} px: export them with "
            "{image_size} {wanted}, or set model.image_size to {size}",
            wanted=model_config.image_size,
            size=size,
        )
    vocab = config.words([d.instruction for d in demos])
    targets = [chunk_targets(d.labels, model_config.chunk) for d in demos]
    images = torch.from_numpy(loaded.frames)
    states = torch.from_numpy(np.concatenate([d.states for d in demos]))
    words = [vocab.encode(d.instruction, model_config.max_words) for d in demos]
    instruction = torch.tensor(
        np.concatenate([np.tile(w, (len(d.states), 1)) for w, d in zip(words, demos, strict=True)])
    )
    actions = torch.from_numpy(np.concatenate([t[0] for t in targets]))
    mask = torch.from_numpy(np.concatenate([t[1] for t in targets]))
    model = SmallVLA(model_config, len(vocab), StateNormalizer.fit(states.numpy())).to(device)
    shifts = torch.Generator().manual_seed(config.seed + 1)
    pad = max(1, round(SHIFT * size / 96))

    def loss_of(batch: torch.Tensor) -> torch.Tensor:
        # The data stays in memory here; each batch goes to the device (a no-op on the CPU).
        shifted = random_shift(images[batch], pad, shifts).to(device)
        predicted = model(shifted, states[batch].to(device), instruction[batch].to(device))
        return chunk_loss(predicted, actions[batch].to(device), mask[batch].to(device), config.loss)

    loss_value = optimise(model, loss_of, len(states), config, log_every=log_every, log=log)
    facts = training_facts(config, demos, len(states), loss_value, started) | {"image_size": size}
    save_checkpoint(out, model.cpu(), vocab, facts)
    return facts
