"""The shared policy's server (batching, privileges), with the test policies of `tests/policies.py` (no simulator)."""

from __future__ import annotations

import asyncio
import json

import numpy as np
import pytest

from langgap.engine.shared_policy import PolicyServer
from langgap.policies.base import PrivilegedContext, TaskContext
from langgap.sim.env import Observation

CONTEXT = TaskContext(
    instruction="put the bowl on the plate",
    suite="libero_spatial",
    init_index=0,
    seed=3,
    max_steps=15,
    privileged=PrivilegedContext(
        task_id="spatial/s0/black-bowl-1-on-plate",
        condition="given",
        goal=("(On akita_black_bowl_1 plate_1)",),
        source_goal=("(On akita_black_bowl_1 plate_1)",),
    ),
)
SEEN = Observation(state=np.zeros(8, dtype=np.float32), privileged={"eef_pos": np.zeros(3)})


def test_the_shared_policy_server_waits_max_wait_ms_for_a_batch():
    async def two_queries_50_ms_apart(max_wait_ms: float) -> int:
        server = PolicyServer("noop", {}, max_batch=2, max_wait_ms=max_wait_ms)
        for slot in (0, 1):
            await server.reset(slot, CONTEXT)

        async def later(slot: int, delay: float):
            await asyncio.sleep(delay)
            return await server.act(slot, SEEN)

        await asyncio.gather(later(0, 0.0), later(1, 0.05))
        return server.calls

    assert asyncio.run(two_queries_50_ms_apart(500)) == 1
    assert asyncio.run(two_queries_50_ms_apart(5)) == 2


@pytest.mark.parametrize("policy", ["ContextRecorder", "PrivilegedContextRecorder"])
def test_the_server_gives_the_goal_and_the_simulator_state_to_privileged_policies_only(policy, tmp_path):
    """Whatever a client sends (here: everything), as `langgap serve` does over the wire."""
    log = tmp_path / "told.jsonl"
    server = PolicyServer(f"tests.policies:{policy}", {"path": str(log)}, max_batch=1, max_wait_ms=0)

    async def episode() -> None:
        await server.reset(0, CONTEXT)
        await server.act(0, SEEN)

    asyncio.run(episode())
    (told,) = [json.loads(line) for line in log.read_text().splitlines()]
    privileged = policy.startswith("Privileged")
    assert told["instruction"] == CONTEXT.instruction
    assert (told["privileged"] is not None, told["simulator_state"]) == (privileged, privileged)
