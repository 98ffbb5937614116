"""Scale-out: the Ray backend's overhead and the shared policy's batching gain, side by side in one run.

    .venv/bin/python bench/bench_scaleout.py ray-overhead [--workers 2] [--policy noop]
    .venv/bin/python bench/bench_scaleout.py batching [--workers 2] [--delay-ms 100] [--episodes 2]

Run Ray benchmarks inside a loopback-only network namespace on shared machines, e.g.
`unshare -n sh -c 'ip link set lo up; .venv/bin/python bench/bench_scaleout.py batching'`.
"""

from __future__ import annotations

import argparse
import time

from bench_harness import SAMPLE_TASKS as TASKS
from bench_harness import timed_eval


def ray_overhead(workers: int, policy: str, episodes: int) -> None:
    local, ran = timed_eval(policy=policy, tasks=TASKS, episodes=episodes, workers=workers)
    on_ray, _ = timed_eval(policy=policy, tasks=TASKS, episodes=episodes, workers=workers, backend="ray")
    print(
        f"| {policy}, {ran} episodes, {workers} workers | local {local:.1f} s | Ray {on_ray:.1f} s | "
        f"Ray overhead {100 * (on_ray / local - 1):+.1f} % |"
    )


def batching(workers: int, delay_ms: float, episodes: int) -> None:
    from langgap.catalog.catalog import load_catalog
    from langgap.engine.plan import build_plan
    from langgap.engine.ray_backend import RayBackend, SharedPolicyOptions
    from langgap.engine.runner import RunnerSetup

    catalog = load_catalog()
    plan = build_plan(catalog.select(TASKS), catalog, episodes=episodes)
    setup = RunnerSetup(catalog=catalog.name, policy="delay", policy_args={"delay_ms": str(delay_ms)}, style="libero")
    results = {}
    for max_batch in (1, workers):
        backend = RayBackend(workers, shared_policy=SharedPolicyOptions(max_batch=max_batch, max_wait_ms=delay_ms / 2))
        start = time.perf_counter()
        steps = sum(r.steps for r in backend.run(plan, setup))
        results[max_batch] = (time.perf_counter() - start, backend.last_server_stats["calls"], steps)
    (one, one_calls, steps), (many, many_calls, _) = results[1], results[workers]
    print(
        f"| shared policy, {delay_ms:.0f} ms per call, {workers} env actors, {len(plan)} episodes, {steps} steps | "
        f"one query per call: {one:.1f} s, {one_calls} calls | batched (<= {workers}): {many:.1f} s, "
        f"{many_calls} calls | gain {one / many:.2f}x |"
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
