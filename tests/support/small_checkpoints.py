"""Small-bc and small-vla checkpoints trained in seconds by the CLI, for tests that load or run them."""

from __future__ import annotations

from pathlib import Path

from tests.support.harness import run_cli


def trained_checkpoint(kind: str, data: Path, out: Path, steps: int, batch_size: int) -> Path:
    """`langgap train <kind>` on the two demonstrations in `data`, one thread, written to `out`."""
    result = run_cli(
        "train", kind, "--data", str(data), "--out", str(out), "--steps", str(steps), "--batch-size", str(batch_size),
        "--threads", "1",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "trained on 2 demonstrations" in result.stdout
    return out
