"""Where a LeRobot checkpoint is, checked without LeRobot: `langgap eval --policy lerobot` refuses a path that holds
none before a run starts (in any environment), instead of every episode failing on it in the workers."""

from __future__ import annotations

from pathlib import Path

from langgap.policies.checkpoints import CheckpointArgumentError, CheckpointError


def pretrained_dir(path: str) -> Path:
    """The directory holding `config.json`: `path` itself or its `pretrained_model/`."""
    root = Path(path).expanduser()
    for candidate in (root, root / "pretrained_model"):
        if (candidate / "config.json").is_file():
            return candidate
    raise CheckpointError(f"no LeRobot checkpoint at {root} (expected config.json there or in pretrained_model/)")


def check_arguments(path: str = "", adapter: str = "", **_: object) -> None:
    """Refuse a `path` that holds no checkpoint (`pretrained_dir`) and an `adapter` that is no directory.

    Args:
        path: The `lerobot` policy's `path` argument.
        adapter: Its `adapter` argument ("": none).
        **_: Its other arguments (nothing to check without loading the checkpoint).

    Raises:
        CheckpointError: No `path`, no checkpoint there, or an `adapter` that is no directory.
    """
    if not path:
        raise CheckpointArgumentError("lerobot needs {path}=DIR, a checkpoint's pretrained_model/ directory")
    pretrained_dir(path)
    if adapter and not Path(adapter).expanduser().is_dir():
        raise CheckpointError(f"no PEFT adapter directory at {adapter}")
