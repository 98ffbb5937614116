"""What training `small-bc` and `small-vla` share: the run's settings, the learning-rate schedule, the chunk loss
and the optimisation loop (AdamW, gradient clipping, a seeded sampler: deterministic for a seed and thread count)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, TypeVar

import numpy as np
import torch

from langgap.demos.compact import read_manifest
from langgap.errors import LangGapError, ParameterError
from langgap.policies.text import VOCABULARIES, Vocabulary, catalog_vocabulary
from langgap.training import LOSSES


@dataclass(frozen=True)
class TrainConfig:
    """What to train on and how long. `tasks` selects demonstrations by task id (None: all); `model`: the
    model's own config (None: its defaults); `vocabulary`: where the model's words come from (one of
    `VOCABULARIES`: every shipped catalog's sentences, or only the training data's, as before)."""

    data: tuple[str, ...]
    tasks: tuple[str, ...] | None = None
    steps: int = 3000
    batch_size: int = 128
    lr: float = 1e-3
    seed: int = 0
    threads: int = 2
    device: str = "cpu"  # where the model trains: "cpu", or a PyTorch device such as "cuda" (same code, same steps)
    loss: str = "l1"  # on the action chunk: one of LOSSES
    model: Any = None
    vocabulary: str = "catalogs"

    def __post_init__(self) -> None:
        if self.loss not in LOSSES:
            raise LangGapError(f"unknown loss {self.loss!r} ({' or '.join(LOSSES)})")
        if self.vocabulary not in VOCABULARIES:
            raise LangGapError(f"unknown vocabulary {self.vocabulary!r} ({' or '.join(VOCABULARIES)})")

    def words(self, training_texts: Sequence[str]) -> Vocabulary:
        """The model's vocabulary: the shipped catalogs' (fixed before training), or that of `training_texts`
        (the training data's sentences and entity names) under `vocabulary: training`."""
        return Vocabulary.from_texts(training_texts) if self.vocabulary == "training" else catalog_vocabulary()

    def torch_device(self) -> torch.device:
        """The training device, checked: one this machine's PyTorch can use, or a LangGapError that says why not."""
        try:
            device = torch.device(self.device)
        except RuntimeError as exc:
            raise ParameterError("{device} {name}: {exc}", name=self.device, exc=exc) from None
        if device.type == "cuda" and not torch.cuda.is_available():
            raise ParameterError("{device} {name}: PyTorch sees no CUDA device on this machine", name=self.device)
        if device.type == "cuda" and device.index is not None and device.index >= torch.cuda.device_count():
            raise ParameterError(
                "{device} {name}: PyTorch sees {count} CUDA device(s) on this machine, numbered from 0",
                name=self.device,
                count=torch.cuda.device_count(),
            )
        if device.type not in ("cpu", "cuda"):
            raise ParameterError("{device} {name}: only cpu and cuda are supported", name=self.device)
        return device

    def seeded_device(self) -> torch.device:
        """The checked training device (`torch_device`), with PyTorch's threads and seed set for the run: what
        makes training deterministic for a seed and thread count. Call it before the model is made."""
        device = self.torch_device()
        torch.set_num_threads(self.threads)
        torch.manual_seed(self.seed)
        return device


class _OfTask(Protocol):
    task_id: str


Item = TypeVar("Item", bound=_OfTask)


def selected(config: TrainConfig, demos: Sequence[Item], log: Callable[[str], None] | None = print) -> list[Item]:
    """The demonstrations of `config.tasks` among `demos` (all if None), each with a `task_id`. A selected task
    that a collection in `config.data` attempted and kept none of (the oracle failed every attempt) is skipped
    with a note: training goes on with what there is. One that no collection attempted is an error (wrong data or
    a mistyped selection), and so is a selection with nothing to train on."""
    kept = list(demos)
    if config.tasks is not None:
        wanted = set(config.tasks)
        kept = [d for d in kept if d.task_id in wanted]
        missing = wanted - {d.task_id for d in kept}
        attempted = {task for root in config.data for task in read_manifest(Path(root))["tasks"]}
        never = missing - attempted
        if never:
            raise LangGapError(f"no demonstrations of {len(never)} selected task(s), e.g. {sorted(never)[0]}")
        if missing and log:
            log(
                f"note: {len(missing)} selected task(s) were collected but kept no demonstration, e.g. "
                f"{sorted(missing)[0]} (see collection.json): training without them"
            )
    if not kept:
        raise LangGapError("no demonstrations to train on")
    return kept


def training_facts(
    config: TrainConfig, demos: Sequence[_OfTask], frames: int, final_loss: float, started: float
) -> dict:
    """What a checkpoint records of its training (`started`: `time.perf_counter()` at its start)."""
    return {
        "data": list(config.data),
        "tasks": sorted({d.task_id for d in demos}),
        "demos": len(demos),
        "frames": frames,
        "steps": config.steps,
        "batch_size": config.batch_size,
        "lr": config.lr,
        "loss": config.loss,
        "vocabulary": config.vocabulary,
        "seed": config.seed,
        "device": config.device,
        "final_loss": final_loss,
        "train_time_s": round(time.perf_counter() - started, 1),
    }


def lr_factor(step: int, total: int) -> float:
    """Linear warm-up over the first 5 % of steps, then cosine decay to 10 % of the peak."""
    warmup = max(1, total // 20)
    if step < warmup:
        return (step + 1) / warmup
    progress = (step - warmup) / max(1, total - warmup)
    return 0.1 + 0.45 * (1 + math.cos(math.pi * progress))


def chunk_targets(labels: np.ndarray, chunk: int) -> tuple[np.ndarray, np.ndarray]:
    """Each frame's next `chunk` labels (the last one repeated past the end) and which of them exist."""
    n = len(labels)
    index = np.arange(n)[:, None] + np.arange(chunk)[None, :]
    return labels[np.minimum(index, n - 1)].astype(np.float32), index < n


def chunk_loss(predicted: torch.Tensor, target: torch.Tensor, mask: torch.Tensor, kind: str) -> torch.Tensor:
    """The mean L1 or squared error over the chunk's actions that exist (`mask`: steps past a demonstration's end
    are left out)."""
    weight = mask.unsqueeze(-1).float()
    error = predicted - target
    error = error.abs() if kind == "l1" else error**2
    return (error * weight).sum() / (weight.sum() * target.shape[-1])


def optimise(
    model: torch.nn.Module,
    loss_of: Callable[[torch.Tensor], torch.Tensor],
    frames: int,
    config: TrainConfig,
    *,
    log_every: int = 200,
    log: Callable[[str], None] | None = print,
) -> float:
    """Train `model` for `config.steps` steps on batches of frame indices drawn from `frames` with the config's
    seed (`loss_of(indices)` gives a batch's loss); returns the last step's loss and leaves the model in eval mode."""
    started = time.perf_counter()
    optimizer = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=1e-4)
    schedule = torch.optim.lr_scheduler.LambdaLR(optimizer, lambda step: lr_factor(step, config.steps))
    generator = torch.Generator().manual_seed(config.seed)
    model.train()
    loss_value = float("nan")
    for step in range(1, config.steps + 1):
        batch = torch.randint(frames, (config.batch_size,), generator=generator)
        loss = loss_of(batch)
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        optimizer.step()
        schedule.step()
        loss_value = loss.detach().item()
        if log and (step % log_every == 0 or step == config.steps):
            log(f"step {step}/{config.steps}  loss {loss_value:.5f}  {time.perf_counter() - started:.0f}s")
    model.eval()
    return loss_value
