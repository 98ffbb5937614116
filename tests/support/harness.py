"""Helpers of the harness tests: the repository, the CLI as a user runs it, a run store's rows, tool requirements."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SHORT_STEPS = 15
TINY_TASK = "spatial/s0/black-bowl-1-on-plate"


def in_ci() -> bool:
    """True under CI (`CI=true`), where a test's missing tool is a failure, not a skip."""
    return os.environ.get("CI", "").lower() in ("1", "true", "yes")


def store_rows(run: Path) -> list[dict]:
    """Every episode row of a run store, as plain dicts, in key order."""
    import sqlite3

    db = sqlite3.connect(Path(run) / "episodes.sqlite")
    db.row_factory = sqlite3.Row
    rows = [dict(r) for r in db.execute("SELECT * FROM episodes ORDER BY task_id, init_index, condition")]
    db.close()
    return rows


def run_cli(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """Run `langgap ARGS` in a fresh interpreter, as a user would."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "src"), str(REPO)])}
    return subprocess.run(
        [sys.executable, "-m", "langgap.cli.main", *args], capture_output=True, text=True, timeout=timeout, env=env
    )


def cli_parsers(parser: argparse.ArgumentParser, prog: str = "langgap"):
    """(command line, parser) for `parser` (`langgap.cli.main.build_parser()`) and every sub-parser below it."""
    yield prog, parser
    for action in parser._actions:  # argparse lists its actions only in this private field
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                yield from cli_parsers(child, f"{prog} {name}")


def tiny_config():
    """The collection settings of `tiny_collection` (two noisy oracle demonstrations of TINY_TASK)."""
    from langgap.demos.collect import CollectConfig

    return CollectConfig(catalog="langgap99", tasks=(TINY_TASK,), demos=2, seed=7, noise=0.2)
