"""Shared rollouts vs one rollout per episode: the same instruction-blind run, side by side in one run.

Runs `--policy` (default `blind`) on the tasks `--tasks` selects (default: every task of one libero_spatial
scene) × `--inits` init states twice, on `--workers` workers: episode by episode, then with shared rollouts
(`--share-rollouts`); checks that both stores hold the same records (the measured fields aside) and prints
both wall times, their ratio and the episodes/h of each.

    .venv/bin/python bench/bench_shared_rollouts.py [--tasks 'spatial/s0/*'] [--inits 2] [--workers 1]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from dataclasses import asdict
from pathlib import Path

from langgap.engine.evaluate import evaluate
from langgap.engine.spec import ExecutionOptions, RunSpec
from langgap.store import RunStore

MEASURED = ("wall_time_s", "finished_at", "worker")


def _timed(spec: RunSpec, run: Path, options: ExecutionOptions) -> tuple[float, list[dict]]:
    """The wall time of the run and its records without the measured fields."""
    start = time.perf_counter()
    summary = evaluate(spec, run, options)
    wall = time.perf_counter() - start
    assert summary.complete, f"{run}: {summary.gaps} gaps"
    with RunStore.open(run) as store:
        return wall, [{k: v for k, v in asdict(r).items() if k not in MEASURED} for r in store.records()]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policy", default="blind")
    parser.add_argument("--catalog", default="langgap99")
    parser.add_argument("--tasks", default="spatial/s0/*")
    parser.add_argument("--inits", type=int, default=2)
    parser.add_argument("--workers", type=int, default=1)
    args = parser.parse_args()
    spec = RunSpec.create(args.policy, catalog=args.catalog, tasks=args.tasks, episodes=args.inits)
    episodes = len(spec.tasks) * args.inits
    with tempfile.TemporaryDirectory() as tmp:
        walls = {}
        records = {}
        for shared in (False, True):
            options = ExecutionOptions(workers=args.workers, progress=False, share_rollouts=shared)
            walls[shared], records[shared] = _timed(spec, Path(tmp) / f"run-{shared}", options)
    assert records[True] == records[False], "shared rollouts gave other records than separate episodes"
    what = f"{args.policy} on {len(spec.tasks)} tasks ({args.tasks}) x {args.inits} init states"
    print(f"{what}, {args.workers} worker(s)")
    for shared, label in ((False, "one rollout per episode"), (True, "shared rollouts")):
        print(f"  {label}: {walls[shared]:.1f} s, {episodes / walls[shared] * 3600:.0f} episodes/h")
    print(f"  records identical (measured fields aside); shared rollouts {walls[False] / walls[True]:.2f}x faster")


if __name__ == "__main__":
    main()
