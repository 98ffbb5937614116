"""small-bc training speed on this machine: seconds per optimisation step, and the time of one configuration.

Trains on a collection for `--steps` steps (default 100) and extrapolates to the step count of the
small-scale reproduction (`experiments/small_scale.sh`), which must stay under 30 minutes on 2 cores.

    .venv/bin/python bench/bench_train.py --data DIR [--steps N] [--threads T] [--target-steps N]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from langgap.training.train_small_bc import TrainConfig, train

BUDGET_S = 30 * 60


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", action="append", required=True)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--target-steps", type=int, default=3000)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        facts = train(
            TrainConfig(data=tuple(args.data), steps=args.steps, threads=args.threads),
            Path(tmp) / "bench.safetensors",
            log=None,
        )
        total = time.perf_counter() - start
    per_step = total / args.steps
    projected = per_step * args.target_steps
    print(f"{facts['demos']} demos, {facts['frames']} frames", end="; ")
    print(f"{args.steps} steps in {total:.1f}s ({per_step * 1000:.0f} ms/step)")
    print(
        f"{args.target_steps} steps: {projected / 60:.1f} min on {args.threads} thread(s) "
        f"({'within' if projected <= BUDGET_S else 'over'} the 30-min budget)"
    )


if __name__ == "__main__":
    main()
