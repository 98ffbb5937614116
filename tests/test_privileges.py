"""Privileges are declared, enforced and shown: the simulator state reaches only policies whose spec says
`sees_state`, the goal only those whose spec says `sees_goal`, in process, through worker processes and
over the wire; records say which privileges a policy had."""

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
from tests.support.policies import RECORDERS, robot_only_state
from tests.support.servers import free_port, helper_server, langgap_serve, running, subprocess_env
from tests.test_openpi import PLAN, TASK_ID, episodes

TASK = "spatial/s0/black-bowl-2-on-plate"


def _recorded(path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


@pytest.mark.parametrize("shared", [False, True], ids=["own-policy", "shared-policy"])
def test_a_policy_is_told_the_goal_and_shown_the_simulator_state_only_as_it_declares(short_catalog, tmp_path, shared):
    for k, (policy, (sees_state, sees_goal)) in enumerate(RECORDERS.items()):
        workers = "2" if shared or k % 2 == 0 else "0"  # in process and in worker processes
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
        assert {(r["sees_state"], r["sees_goal"]) for r in store_rows(run)} == {(sees_state, sees_goal)}
        assert {c["simulator_state"] for c in contexts} == {sees_state}  # the real env's observations
        if sees_goal:
            assert {c["privileged"]["task_id"] for c in contexts} == {TASK}
            assert {c["privileged"]["condition"] for c in contexts} == {"given", "shuffled"}
            assert all(c["privileged"]["goal"] == ["(On akita_black_bowl_2 plate_1)"] for c in contexts)
        else:
            assert all(c["privileged"] is None for c in contexts)
            assert TASK not in json.dumps(contexts) and "plate_1" not in json.dumps(contexts)


@pytest.mark.parametrize("policy,privileged", [("oracle", (1, 1)), ("random", (0, 0))])
def test_records_say_which_privileges_a_builtin_policy_had(short_catalog, tmp_path, policy, privileged):
    run = tmp_path / "run"
    result = run_cli(
        "eval", "--policy", policy, "--catalog", short_catalog, "--tasks", TASK, "--episodes", "1",
        "--run", str(run), "--workers", "0", "--no-progress", "--quiet",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert [(r["policy"], r["sees_state"], r["sees_goal"]) for r in store_rows(run)] == [(policy, *privileged)]


@pytest.mark.parametrize("policy", RECORDERS)
def test_the_openpi_client_sends_the_goal_and_the_state_only_as_the_served_spec_declares(catalog, tmp_path, policy):
    sees_state, sees_goal = RECORDERS[policy]
    port, record = free_port(), tmp_path / "record"
    record.mkdir()
    server = helper_server("langgap-record", port, f"tests.support.policies:{policy}", f"path={tmp_path / 'told'}")
    with running(server, port, env=subprocess_env(RECORD_DIR=str(record))):
        remote = OpenpiPolicy(port=port)
        episodes(remote, catalog, PLAN[:1])
        # The client's own guard: handed everything, as by a careless caller.
        remote.reset(task_context(catalog.get(TASK_ID), catalog, init_index=0, seed=0))
        remote.act(Observation(state=np.zeros(8, dtype=np.float32), privileged=robot_only_state()))
        remote.close()
    sent = _recorded(record / "requests.jsonl")
    public = {protocol.STATE_KEY, protocol.PROMPT_KEY, protocol.EPISODE_KEY, protocol.CONTEXT_KEY}
    assert sent and all(set(r) == public | ({protocol.PRIVILEGED_KEY} if sees_state else set()) for r in sent)
    if sees_state:  # the real env's whole simulator state, then the careless caller's
        assert "body/plate_1" in sent[0][protocol.PRIVILEGED_KEY] and set(sent[-1][protocol.PRIVILEGED_KEY]) == {
            "eef_pos",
            "eef_mat",
            "gripper_qpos",
            "base_pos",
        }
    if sees_goal:
        told = sent[0][protocol.CONTEXT_KEY]["privileged"]
        assert told["task_id"] == TASK_ID and told["goal"] == ["(On akita_black_bowl_1 plate_1)"]
    else:
        assert all(r[protocol.CONTEXT_KEY]["privileged"] is None for r in sent)
        wire = json.dumps(sent)  # every request, whole: the answer appears nowhere in it
        assert TASK_ID not in wire and "(On " not in wire and "goal" not in wire


@pytest.mark.parametrize("policy", RECORDERS)
def test_langgap_serve_drops_the_goal_and_the_state_a_client_sends_to_a_policy_that_does_not_declare_them(
    catalog, tmp_path, policy
):
    log, port = tmp_path / "served.jsonl", free_port()
    full = task_context(catalog.get(TASK), catalog, init_index=0, seed=0)  # as a careless client might send
    request = {
        protocol.EPISODE_KEY: "e1",
        protocol.CONTEXT_KEY: protocol.context_to_message(full),
        protocol.STATE_KEY: np.zeros(8, dtype=np.float32),
        protocol.PRIVILEGED_KEY: protocol.privileged_to_message(robot_only_state()),
    }
    server = running(langgap_serve(port, f"tests.support.policies:{policy}", f"path={log}"), port)
    with server, connect(f"ws://127.0.0.1:{port}", proxy=None) as ws:
        ws.recv(timeout=5)  # the metadata
        ws.send(protocol.pack(request))
        assert protocol.ACTIONS_KEY in protocol.unpack(ws.recv(timeout=10))
    (told,) = _recorded(log)
    sees_state, sees_goal = RECORDERS[policy]
    assert told["instruction"] == full.instruction and told["simulator_state"] == sees_state
    assert told["privileged"] == (json.loads(json.dumps(dataclasses.asdict(full.privileged))) if sees_goal else None)


def test_langgap_serve_listens_on_loopback_unless_told_otherwise():
    port = free_port()
    with running(langgap_serve(port, "noop"), port) as server:
        listening = subprocess.run(["ss", "-ltnpH"], capture_output=True, text=True, check=True).stdout
    mine = [line.split()[3] for line in listening.splitlines() if f"pid={server.pid}," in line]
    assert mine == [f"127.0.0.1:{port}"]
