"""One-file checkpoints of LangGap's own policies: safetensors weights with JSON metadata (`format`, the model's
config, its vocabulary and how it was trained)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from langgap.errors import LangGapError, PolicyArgumentError
from langgap.policies.text import Vocabulary


class CheckpointError(LangGapError):
    """A checkpoint is missing, unreadable, or not one of the kind asked for (a LeRobot one: incompatible with
    LIBERO)."""


class CheckpointArgumentError(CheckpointError, PolicyArgumentError):
    """A policy that loads a checkpoint was given no argument naming one (named as the policy's argument)."""


def write_checkpoint(
    path: str | Path, state: dict, *, format: str, config: dict, vocab: list[str], training: dict
) -> Path:
    """Write tensors `state` and the metadata to one safetensors file (parents created)."""
    from safetensors.torch import save_file

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    metadata = {
        "format": format,
        "config": json.dumps(config),
        "vocab": json.dumps(vocab),
        "training": json.dumps(training, sort_keys=True),
    }
    save_file({k: v.contiguous() for k, v in state.items()}, str(path), metadata=metadata)
    return path


def save_model(path: str | Path, model, vocab, training: dict, *, format: str) -> Path:
    """Write `model` (a torch module with a dataclass `config`), its vocabulary and training facts to `path`."""
    from dataclasses import asdict

    return write_checkpoint(
        path, model.state_dict(), format=format, config=asdict(model.config), vocab=vocab.tokens, training=training
    )


def load_model(path: str | Path, *, format: str, kind: str, build: Callable[[dict, int, dict], Any]) -> tuple:
    """(model in eval mode, vocabulary, training facts) of a checkpoint `save_model` wrote; `build(config, vocabulary
    size, tensors)` makes the untrained model (its normalisation statistics come from the tensors)."""
    state, config, vocab, training = read_checkpoint(path, format=format, kind=kind)
    model = build(config, len(vocab), state)
    model.load_state_dict(state)
    model.eval()
    return model, Vocabulary(vocab), training


def read_checkpoint(path: str | Path, *, format: str, kind: str) -> tuple[dict, dict, list[str], dict]:
    """(tensors, config, vocabulary, training facts) of a checkpoint `write_checkpoint` wrote with `format`;
    anything else is a CheckpointError that names `kind` (the policy's name)."""
    from safetensors import safe_open
    from safetensors.torch import load_file

    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"no {kind} checkpoint at {path}")
    try:
        with safe_open(str(path), framework="pt") as f:
            metadata = f.metadata() or {}
        if metadata.get("format") != format:
            raise CheckpointError(f"{path} is not a {kind} checkpoint (format {metadata.get('format')!r})")
        state = load_file(str(path))
    except (OSError, ValueError, RuntimeError) as exc:
        raise CheckpointError(f"cannot read {kind} checkpoint {path}: {exc}") from None
    return state, json.loads(metadata["config"]), json.loads(metadata["vocab"]), json.loads(metadata["training"])
