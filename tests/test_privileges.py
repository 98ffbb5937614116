"""Privileges are declared, enforced and shown: the goal reaches only policies whose spec says
`privileged`, in process, through worker processes and over the wire; records say who was privileged."""

from __future__ import annotations

import dataclasses
import json
import subprocess

import numpy as np
import pytest
from websockets.sync.client import connect

from langgap.engine.context import task_context
from langgap.policies import protocol
from langgap.policies.openpi import OpenpiPolicy
from langgap.sim.env import Observation
from tests.support.harness import run_cli, store_rows
from tests.support.servers import free_port, helper_server, langgap_serve, running, subprocess_env
from tests.test_openpi import PLAN, TASK_ID, episodes

TASK = "spatial/s0/black-bowl-2-on-plate"


def _recorded(path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


@pytest.mark.parametrize("shared", [False, True], ids=["own-policy", "shared-policy"])
def test_only_a_privileged_policy_is_told_the_goal_or_shown_the_simulator_state(short_catalog, tmp_path, shared):
    for policy, workers in (("ContextRecorder", "2"), ("PrivilegedContextRecorder", "2" if shared else "0")):
        log, run = tmp_path / f"{policy}.jsonl", tmp_path / policy
        result = run_cli(
            "eval", "--policy", f"tests.support.policies:{policy}", "--policy-arg", f"path={log}",
            "--catalog", short_catalog,
            "--tasks", TASK, "--episodes", "2", "--condition", "given", "--condition", "shuffled", "--run", str(run),
            "--workers", workers, "--no-progress", "--quiet", *(["--shared-policy"] if shared else []),
        )  # fmt: skip
        assert result.returncode == 0, result.stderr
        contexts = _recorded(log)
        assert len(contexts) == 4 and all(c["instruction"] for c in contexts)
        privileged = policy.startswith("Privileged")
        assert {r["privileged"] for r in store_rows(run)} == {int(privileged)}
        assert {c["simulator_state"] for c in contexts} == {privileged}  # the real env's observations
        if privileged:
            assert {c["privileged"]["task_id"] for c in contexts} == {TASK}
            assert {c["privileged"]["condition"] for c in contexts} == {"given", "shuffled"}
            assert all(c["privileged"]["goal"] == ["(On akita_black_bowl_2 plate_1)"] for c in contexts)
        else:
            assert all(c["privileged"] is None for c in contexts)
            assert TASK not in json.dumps(contexts) and "plate_1" not in json.dumps(contexts)


@pytest.mark.parametrize("policy,privileged", [("oracle", 1), ("random", 0)])
def test_records_say_whether_a_builtin_policy_was_privileged(short_catalog, tmp_path, policy, privileged):
    run = tmp_path / "run"
    result = run_cli(
        "eval", "--policy", policy, "--catalog", short_catalog, "--tasks", TASK, "--episodes", "1",
        "--run", str(run), "--workers", "0", "--no-progress", "--quiet",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert [(r["policy"], r["privileged"]) for r in store_rows(run)] == [(policy, privileged)]


def test_the_openpi_client_sends_the_goal_only_to_a_privileged_served_policy(catalog, tmp_path):
    sent = {}
    for name in ("random", "oracle"):
        port, record = free_port(), tmp_path / name
        record.mkdir()
        with running(helper_server("langgap-record", port, name), port, env=subprocess_env(RECORD_DIR=str(record))):
            remote = OpenpiPolicy(port=port)
            episodes(remote, catalog, PLAN[:1])
            if name == "random":  # the client's own guard: handed everything, as by a careless caller
                remote.reset(task_context(catalog.get(TASK_ID), catalog, init_index=0, seed=0))
                remote.act(Observation(state=np.zeros(8, dtype=np.float32), privileged={"body/plate_1": np.zeros(7)}))
            remote.close()
        sent[name] = _recorded(record / "requests.jsonl")
    public = {protocol.STATE_KEY, protocol.PROMPT_KEY, protocol.EPISODE_KEY, protocol.CONTEXT_KEY}
    assert sent["random"] and all(set(r) == public for r in sent["random"])
    assert all(r[protocol.CONTEXT_KEY]["privileged"] is None for r in sent["random"])
    wire = json.dumps(sent["random"])  # every request, whole: the answer appears nowhere in it
    assert TASK_ID not in wire and "(On " not in wire and "goal" not in wire
    assert all(set(r) == public | {protocol.PRIVILEGED_KEY} for r in sent["oracle"])
    told = sent["oracle"][0][protocol.CONTEXT_KEY]["privileged"]
    assert told["task_id"] == TASK_ID and told["goal"] == ["(On akita_black_bowl_1 plate_1)"]


@pytest.mark.parametrize("policy", ["ContextRecorder", "PrivilegedContextRecorder"])
def test_langgap_serve_drops_the_privileged_part_a_client_sends_to_a_policy_that_is_not(catalog, tmp_path, policy):
    log, port = tmp_path / "served.jsonl", free_port()
    full = task_context(catalog.get(TASK), catalog, init_index=0, seed=0)  # as a careless client might send
    request = {
        protocol.EPISODE_KEY: "e1",
        protocol.CONTEXT_KEY: protocol.context_to_message(full),
        protocol.STATE_KEY: np.zeros(8, dtype=np.float32),
        protocol.PRIVILEGED_KEY: {"body/plate_1": np.zeros(7)},
    }
    server = running(langgap_serve(port, f"tests.support.policies:{policy}", f"path={log}"), port)
    with server, connect(f"ws://127.0.0.1:{port}", proxy=None) as ws:
        ws.recv(timeout=5)  # the metadata
        ws.send(protocol.pack(request))
        assert protocol.ACTIONS_KEY in protocol.unpack(ws.recv(timeout=10))
    (told,) = _recorded(log)
    privileged = policy.startswith("Privileged")
    assert told["instruction"] == full.instruction and told["simulator_state"] == privileged
    assert told["privileged"] == (json.loads(json.dumps(dataclasses.asdict(full.privileged))) if privileged else None)


def test_langgap_serve_listens_on_loopback_unless_told_otherwise():
    port = free_port()
    with running(langgap_serve(port, "noop"), port) as server:
        listening = subprocess.run(["ss", "-ltnpH"], capture_output=True, text=True, check=True).stdout
    mine = [line.split()[3] for line in listening.splitlines() if f"pid={server.pid}," in line]
    assert mine == [f"127.0.0.1:{port}"]
