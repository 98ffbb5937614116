"""Training `small-bc` by behaviour cloning on collected demonstrations (CPU).

Every frame of every selected demonstration is a sample: its observation, its instruction, and the
next `chunk` actions (the loss ignores steps past the demonstration's end). Deterministic for a given
seed and thread count.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch

from langgap.demos.compact import load_demos, read_manifest
from langgap.demos.record import Demo
from langgap.errors import LangGapError
from langgap.policies.small_bc import features
from langgap.policies.small_bc.model import ModelConfig, Normalizer, SmallBC, save_checkpoint
from langgap.policies.small_bc.text import Vocabulary


@dataclass(frozen=True)
class TrainConfig:
    """What to train on and how long. `tasks` selects demonstrations by task id (None: all)."""

    data: tuple[str, ...]
    tasks: tuple[str, ...] | None = None
    steps: int = 3000
    batch_size: int = 128
    lr: float = 1e-3
    seed: int = 0
    threads: int = 2
    loss: str = "l1"  # l1 or mse, on the action chunk
    model: ModelConfig = field(default_factory=ModelConfig)


@dataclass
class Samples:
    """All frames as arrays (N = frames, E = max entities, W = name words, L = instruction words)."""

    proprio: np.ndarray  # (N, 14)
    entities: np.ndarray  # (N, E, 11)
    names: np.ndarray  # (N, E, W) word ids
    instruction: np.ndarray  # (N, L) word ids
    actions: np.ndarray  # (N, chunk, 7)
    action_mask: np.ndarray  # (N, chunk)


def build_vocabulary(demos: list[Demo]) -> Vocabulary:
    names = {features.name_words(n) for d in demos for n in features.entity_names(d.privileged)}
    return Vocabulary.from_texts([d.instruction for d in demos] + sorted(names))


def build_samples(demos: list[Demo], vocab: Vocabulary, config: ModelConfig) -> Samples:
    """Turn demonstrations into training arrays."""
    max_entities = max(len(features.entity_names(d.privileged)) for d in demos)
    parts: dict[str, list[np.ndarray]] = {k: [] for k in Samples.__dataclass_fields__}
    steps = np.arange(config.chunk)
    for demo in demos:
        n = demo.length
        names = features.entity_names(demo.privileged)
        ents = np.zeros((n, max_entities, features.ENTITY_DIM), dtype=np.float32)
        ents[:, : len(names)] = features.entities(demo.privileged, names)
        name_ids = np.zeros((max_entities, config.max_name_words), dtype=np.int64)
        for i, name in enumerate(names):
            name_ids[i] = vocab.encode(features.name_words(name), config.max_name_words)
        index = np.arange(n)[:, None] + steps[None, :]
        parts["proprio"].append(features.proprio(demo.privileged))
        parts["entities"].append(ents)
        parts["names"].append(np.broadcast_to(name_ids, (n, *name_ids.shape)))
        parts["instruction"].append(np.tile(vocab.encode(demo.instruction, config.max_words), (n, 1)))
        parts["actions"].append(demo.labels[np.minimum(index, n - 1)].astype(np.float32))
        parts["action_mask"].append(index < n)
    return Samples(**{k: np.concatenate(v) for k, v in parts.items()})


def select_demos(config: TrainConfig, log=print) -> list[Demo]:
    """The demonstrations of `config.tasks` (all if None). A selected task that a collection attempted
    and kept none of (the oracle failed every attempt) is skipped with a note: training goes on with
    what there is. One that no collection attempted is an error (wrong data or a mistyped selection)."""
    roots = [Path(p) for p in config.data]
    demos = load_demos(roots)
    if config.tasks is not None:
        wanted = set(config.tasks)
        demos = [d for d in demos if d.task_id in wanted]
        missing = wanted - {d.task_id for d in demos}
        never = missing - _attempted(roots) if missing else set()
        if never:
            raise LangGapError(f"no demonstrations of {len(never)} selected task(s), e.g. {sorted(never)[0]}")
        if missing and log:
            log(
                f"note: {len(missing)} selected task(s) were collected but kept no demonstration, e.g. "
                f"{sorted(missing)[0]} (see collection.json): training without them"
            )
    if not demos:
        raise LangGapError("no demonstrations to train on")
    return demos


def _attempted(roots: list[Path]) -> set[str]:
    """Every task the collections in `roots` attempted, whether or not they kept a demonstration."""
    return {task for root in roots for task in read_manifest(root).get("tasks", {})}


def _lr_factor(step: int, total: int) -> float:
    """Linear warm-up over the first 5 % of steps, then cosine decay to 10 % of the peak."""
    warmup = max(1, total // 20)
    if step < warmup:
        return (step + 1) / warmup
    progress = (step - warmup) / max(1, total - warmup)
    return 0.1 + 0.45 * (1 + math.cos(math.pi * progress))


def train(config: TrainConfig, out: str | Path, *, log_every: int = 200, log=print) -> dict:
    """Train a small-bc model on `config`'s demonstrations and save it to `out`; returns training facts."""
    if config.loss not in ("l1", "mse"):
        raise LangGapError(f"unknown loss {config.loss!r} (l1 or mse)")
    started = time.perf_counter()
    torch.set_num_threads(config.threads)
    torch.manual_seed(config.seed)
    demos = select_demos(config, log)
    vocab = build_vocabulary(demos)
    samples = build_samples(demos, vocab, config.model)
    tensors = {k: torch.from_numpy(np.ascontiguousarray(v)) for k, v in asdict(samples).items()}
    normalizer = Normalizer.fit(samples.proprio, samples.entities, samples.names[..., 0] > 0)
    model = SmallBC(config.model, len(vocab), normalizer)
    optimizer = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=1e-4)
    schedule = torch.optim.lr_scheduler.LambdaLR(optimizer, lambda step: _lr_factor(step, config.steps))
    generator = torch.Generator().manual_seed(config.seed)
    frames = len(samples.proprio)
    model.train()
    loss_value = float("nan")
    for step in range(1, config.steps + 1):
        batch = torch.randint(frames, (config.batch_size,), generator=generator)
        pred = model(
            tensors["proprio"][batch],
            tensors["entities"][batch],
            tensors["names"][batch],
            tensors["instruction"][batch],
        )
        mask = tensors["action_mask"][batch].unsqueeze(-1).float()
        error = pred - tensors["actions"][batch]
        error = error.abs() if config.loss == "l1" else error**2
        loss = (error * mask).sum() / (mask.sum() * 7)
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        optimizer.step()
        schedule.step()
        loss_value = loss.detach().item()
        if log and (step % log_every == 0 or step == config.steps):
            log(f"step {step}/{config.steps}  loss {loss_value:.5f}  {time.perf_counter() - started:.0f}s")
    model.eval()
    facts = {
        "data": list(config.data),
        "tasks": sorted({d.task_id for d in demos}),
        "demos": len(demos),
        "frames": frames,
        "steps": config.steps,
        "batch_size": config.batch_size,
        "lr": config.lr,
        "loss": config.loss,
        "seed": config.seed,
        "final_loss": loss_value,
        "train_time_s": round(time.perf_counter() - started, 1),
    }
    save_checkpoint(out, model, vocab, facts)
    return facts
