"""The execution flags of every command that runs work on the engine (`eval`, `validate`, `collect`,
`generate --gate-inits`): where and how its work items run. None of them changes a result."""

from __future__ import annotations

import argparse

from langgap.engine.pools import BACKENDS
from langgap.engine.spec import (
    DEFAULT_FAILURE_STREAK,
    DEFAULT_MAX_ATTEMPTS,
    DEFAULT_TIMEOUT_S,
    ExecutionOptions,
)


def add_execution_options(
    parser: argparse.ArgumentParser, *, attempts_flag: str = "--max-attempts", attempts_help: str | None = None
) -> None:
    """Add the execution flags: backend, workers, timeout, retries, fail-fast, Ray's address, progress.
    `attempts_flag` names the retries' flag where the command's own `--max-attempts` means something else, and
    `attempts_help` says what its retries are where the work is not episodes."""
    parser.add_argument(
        "--backend",
        choices=sorted(BACKENDS),
        default="local",
        help="local worker processes, or actors on a Ray cluster (pip install 'langgap[ray]')",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=1,
        help="local worker processes (0: this process) or Ray actors (default: %(default)s)",
    )
    parser.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help=f"seconds per episode (a longer work item: per episode it may run) before it is an infrastructure "
        f"failure (default: {DEFAULT_TIMEOUT_S:g}; needs worker processes)",
    )
    parser.add_argument(
        attempts_flag,
        dest="work_attempts",
        metavar="N",
        type=int,
        default=DEFAULT_MAX_ATTEMPTS,
        help=attempts_help
        or "tries at each episode (or other work item) when the machinery fails (a crash, a timeout; not the "
        "policy's failure) before it is given up: an episode is then stored as a gap, with no verdict on the policy, "
        "which --resume runs again; other work stops the command with an error (default: %(default)s)",
    )
    parser.add_argument(
        "--max-failure-streak",
        type=int,
        default=DEFAULT_FAILURE_STREAK,
        metavar="N",
        help="stop after N consecutive infrastructure failures with the same cause (default: %(default)s)",
    )
    parser.add_argument("--ray-address", metavar="ADDR", help="Ray cluster to join (default: start a local one)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def add_share_rollouts_option(parser: argparse.ArgumentParser) -> None:
    """Add `--share-rollouts` (commands that run a policy's episodes: `eval`, `validate`)."""
    parser.add_argument(
        "--share-rollouts",
        action="store_true",
        help="run the episodes of an instruction-blind policy (noop, random, blind: PolicySpec.reads_instruction) "
        "that start alike (scene, init state, seed) as one rollout judged for each of their tasks; every record "
        "is the one its own episode gives (a policy that reads its instruction runs every episode on its own)",
    )


def execution_options(args: argparse.Namespace, **more) -> ExecutionOptions:
    """The `ExecutionOptions` of the flags `add_execution_options` added, with `more` (a command's own)."""
    return ExecutionOptions(
        backend=args.backend,
        workers=args.workers,
        timeout_s=args.timeout,
        max_attempts=args.work_attempts,
        max_failure_streak=args.max_failure_streak,
        ray_address=args.ray_address,
        progress=not args.no_progress,
        **more,
    )
