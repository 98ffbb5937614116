"""Scale-out: the Ray backend's overhead and the shared policy's batching gain, side by side in one run.

    .venv/bin/python bench/bench_scaleout.py ray-overhead [--workers 2] [--policy noop]
    .venv/bin/python bench/bench_scaleout.py batching [--workers 2] [--delay-ms 100] [--episodes 2]

Run Ray benchmarks inside a loopback-only network namespace on shared machines, e.g.
`unshare -n sh -c 'ip link set lo up; .venv/bin/python bench/bench_scaleout.py batching'`.
"""

from __future__ import annotations

import argparse

from bench_harness import SAMPLE_TASKS as TASKS
from bench_harness import timed_eval


def ray_overhead(workers: int, policy: str, episodes: int) -> None:
    local, summary = timed_eval(policy=policy, tasks=TASKS, episodes=episodes, workers=workers)
    on_ray, _ = timed_eval(policy=policy, tasks=TASKS, episodes=episodes, workers=workers, backend="ray")
    print(
        f"| {policy}, {summary.ran} episodes, {workers} workers | local {local:.1f} s | Ray {on_ray:.1f} s | "
        f"Ray overhead {100 * (on_ray / local - 1):+.1f} % |"
    )


def batching(workers: int, delay_ms: float, episodes: int) -> None:
    results = {}
    for max_batch in (1, workers):
        results[max_batch] = timed_eval(
            policy="delay",
            policy_args={"delay_ms": str(delay_ms)},
            tasks=TASKS,
            episodes=episodes,
            backend="ray",
            workers=workers,
            shared_policy=True,
            max_batch=max_batch,
            max_wait_ms=delay_ms / 2,
        )
    (one, one_run), (many, many_run) = results[1], results[workers]
    print(
        f"| shared policy, {delay_ms:.0f} ms per call, {workers} env actors, {one_run.ran} episodes, "
        f"{one_run.policy_server['queries']} queries | one query per call: {one:.1f} s, "
        f"{one_run.policy_server['calls']} calls | batched (<= {workers}): {many:.1f} s, "
        f"{many_run.policy_server['calls']} calls | gain {one / many:.2f}x |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("ray-overhead", "batching"))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--policy", default="noop")
    parser.add_argument("--episodes", type=int, default=2)
    parser.add_argument("--delay-ms", type=float, default=100.0)
    args = parser.parse_args()
    if args.what == "ray-overhead":
        ray_overhead(args.workers, args.policy, args.episodes)
    else:
        batching(args.workers, args.delay_ms, args.episodes)


if __name__ == "__main__":
    main()
