"""The shared policy's server (batching, privileges) and the local pool's policy process: a real spawned
process and real Unix-socket clients, with the test policies of `tests/support/policies.py` (no simulator)."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import threading
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from langgap.engine.pools.policy_process import GONE, PolicyProcess, SocketPolicyClient
from langgap.engine.shared_policy import PolicyServer
from langgap.errors import LangGapError, PolicyServerError
from langgap.policies import make_policy
from langgap.policies.base import PrivilegedContext, TaskContext, config_hash, policy_config
from langgap.sim.env import Observation
from tests.support.policies import RECORDERS, robot_only_state

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
        goal_expression="(And (On akita_black_bowl_1 plate_1))",
    ),
)
SEEN = Observation(state=np.zeros(8, dtype=np.float32), privileged=robot_only_state())


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


@pytest.mark.parametrize("policy", RECORDERS)
def test_the_server_gives_the_goal_and_the_simulator_state_only_to_policies_that_declare_them(policy, tmp_path):
    """Whatever a client sends (here: everything), as `langgap serve` does over the wire."""
    log = tmp_path / "told.jsonl"
    server = PolicyServer(f"tests.support.policies:{policy}", {"path": str(log)}, max_batch=1, max_wait_ms=0)

    async def episode() -> None:
        await server.reset(0, CONTEXT)
        await server.act(0, SEEN)

    asyncio.run(episode())
    (told,) = [json.loads(line) for line in log.read_text().splitlines()]
    sees_state, sees_goal = RECORDERS[policy]
    assert told["instruction"] == CONTEXT.instruction
    assert (told["simulator_state"], told["privileged"] is not None) == (sees_state, sees_goal)


@pytest.fixture
def policy_process(tmp_path):
    """A `BatchRecorder` (random actions, batched calls logged to a file) in its own process, at most
    two queries per call, each waiting up to 2 s for the other."""
    process = PolicyProcess(
        "tests.support.policies:BatchRecorder", {"path": str(tmp_path / "batches")}, max_batch=2, max_wait_ms=2000
    )
    yield process
    process.close()


def _act_together(clients: list[SocketPolicyClient]) -> list[np.ndarray]:
    actions: list = [None] * len(clients)

    def act(k: int) -> None:
        actions[k] = clients[k].act(SEEN)

    threads = [threading.Thread(target=act, args=(k,)) for k in range(len(clients))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=30)
    return actions


def test_the_policy_process_batches_its_clients_queries_and_reports_its_counters(policy_process, tmp_path):
    clients = [policy_process.address.connect(worker) for worker in (0, 1)]
    assert [c.spec.chunk for c in clients] == [1, 1]
    for k, client in enumerate(clients):
        client.reset(replace(CONTEXT, seed=k))
    actions = _act_together(clients)
    assert (tmp_path / "batches").read_text() == "2\n"  # one batched call answered both workers
    assert not np.array_equal(actions[0], actions[1])  # each connection has its own policy instance (own seed)
    for client in clients:
        client.close()
    socket_dir = Path(policy_process.address.path).parent
    assert policy_process.close() == {"calls": 1, "queries": 2}
    assert not socket_dir.exists()
    with pytest.raises(PolicyServerError, match=GONE):
        policy_process.address.connect(0)


def test_the_shared_policy_has_the_config_hash_of_the_policy_itself(policy_process, tmp_path):
    """Batching is an execution option: the same policy must not look like another with --shared-policy."""
    client = policy_process.address.connect(0)
    own = make_policy("tests.support.policies:BatchRecorder", {"path": str(tmp_path / "batches")})
    assert config_hash(policy_config(client)) == config_hash(policy_config(own))
    client.close()


def test_a_policy_error_is_an_error_of_the_query_and_the_process_serves_on(tmp_path):
    process = PolicyProcess("tests.support.policies:RaisingPolicy", {}, max_batch=4, max_wait_ms=0)
    try:
        client = process.address.connect(0)
        client.reset(CONTEXT)
        for _ in range(2):
            with pytest.raises(PolicyServerError, match="^shared policy failed: RuntimeError: model exploded$"):
                client.act(SEEN)
    finally:
        assert process.close() == {"calls": 2, "queries": 2}


def test_a_killed_policy_process_is_one_cause_for_every_client(policy_process):
    client = policy_process.address.connect(0)
    client.reset(CONTEXT)
    os.kill(policy_process.pid, signal.SIGKILL)
    time.sleep(0.5)
    with pytest.raises(PolicyServerError, match=f"^{GONE}$"):
        client.act(SEEN)
    with pytest.raises(PolicyServerError, match=f"^{GONE}$"):
        policy_process.address.connect(1)
    assert policy_process.close() == {}  # no counters from a dead process; its socket is removed all the same
    assert not Path(policy_process.address.path).parent.exists()


@pytest.mark.parametrize(
    ("policy", "why"),
    [
        ("UnbuildablePolicy", "FileNotFoundError: no checkpoint at /nowhere"),
        ("DyingOnBuildPolicy", "it exited with code 17"),
    ],
)
def test_a_policy_that_cannot_be_built_is_one_error_line(policy, why):
    with pytest.raises(LangGapError) as error:
        PolicyProcess(f"tests.support.policies:{policy}", {}, max_batch=2, max_wait_ms=5)
    assert str(error.value) == f"the shared policy process could not start: {why}"
