"""Training speed on this machine: seconds per optimisation step, and the time of one configuration.

Trains `small-bc` (or `small-vla`) on a collection for `--steps` steps (default 100) and extrapolates to the step
count of the small-scale reproduction (`experiments/small_scale.sh`, `experiments/small_scale_vla.sh`), whose every
configuration must stay under its budget on 2 cores: 30 minutes for small-bc, 45 for small-vla. For small-vla it
also prints the process's peak memory beside the size of the training images, which it holds in memory once.

    .venv/bin/python bench/bench_train.py --data DIR [--policy small-vla] [--steps N] [--threads T] [--batch-size B]
        [--target-steps N]
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

from langgap.training.loop import TrainConfig

BUDGET_MIN = {"small-bc": 30, "small-vla": 45}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", action="append", required=True)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--target-steps", type=int, default=3000)
    parser.add_argument("--policy", choices=sorted(BUDGET_MIN), default="small-bc")
    parser.add_argument("--batch-size", type=int, default=128)
    args = parser.parse_args()
    if args.policy == "small-vla":
        from langgap.training.train_small_vla import train
    else:
        from langgap.training.train_small_bc import train
    budget = BUDGET_MIN[args.policy]
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        facts = train(
            TrainConfig(data=tuple(args.data), steps=args.steps, threads=args.threads, batch_size=args.batch_size),
            Path(tmp) / "bench.safetensors",
            log=None,
        )
        total = time.perf_counter() - start
    per_step = total / args.steps
    projected = per_step * args.target_steps
    print(f"{args.policy}, batch {args.batch_size}: {facts['demos']} demos, {facts['frames']} frames", end="; ")
    print(f"{args.steps} steps in {total:.1f}s ({per_step * 1000:.0f} ms/step)")
    print(
        f"{args.target_steps} steps: {projected / 60:.1f} min on {args.threads} thread(s) "
        f"({'within' if projected <= budget * 60 else 'over'} the {budget}-min budget)"
    )
    if args.policy == "small-vla":
        images = facts["frames"] * 2 * facts["image_size"] ** 2 * 3  # uint8, both cameras
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux reports KiB
        print(f"peak memory {peak / 2**30:.2f} GiB; the images {images / 2**30:.2f} GiB ({peak / images:.2f}x)")


if __name__ == "__main__":
    main()
