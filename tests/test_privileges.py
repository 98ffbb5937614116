"""Privileges are declared, enforced and shown: the goal reaches only policies whose spec says
`privileged`, in process, through worker processes and over the wire; records say who was privileged."""

from __future__ import annotations

import json
import subprocess

import numpy as np

from langgap.engine.context import task_context
from langgap.policies import protocol
from langgap.policies.openpi import OpenpiPolicy
from langgap.serve import ServedPolicy
from tests.conftest import run_cli, store_rows
from tests.policies import ContextRecorder
from tests.servers import free_port, helper_server, langgap_serve, running, subprocess_env
from tests.test_openpi import PLAN, episodes

TASK = "spatial/s0/black-bowl-2-on-plate"


def _recorded(path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_only_a_privileged_policy_is_told_the_goal_and_its_records_say_so(short_catalog, tmp_path):
    for policy, workers in (("ContextRecorder", "2"), ("PrivilegedContextRecorder", "0")):
        log, run = tmp_path / f"{policy}.jsonl", tmp_path / policy
        result = run_cli(
            "eval", "--policy", f"tests.policies:{policy}", "--policy-arg", f"path={log}", "--catalog", short_catalog,
            "--tasks", TASK, "--episodes", "2", "--condition", "given", "--condition", "shuffled", "--run", str(run),
            "--workers", workers, "--no-progress", "--quiet",
        )  # fmt: skip
        assert result.returncode == 0, result.stderr
        contexts = _recorded(log)
        assert len(contexts) == 4 and all(c["instruction"] for c in contexts)
        privileged = policy.startswith("Privileged")
        assert {r["privileged"] for r in store_rows(run)} == {int(privileged)}
        if privileged:
            assert {c["privileged"]["task_id"] for c in contexts} == {TASK}
            assert {c["privileged"]["condition"] for c in contexts} == {"given", "shuffled"}
            assert all(c["privileged"]["goal"] == ["(On akita_black_bowl_2 plate_1)"] for c in contexts)
        else:
            assert all(c["privileged"] is None for c in contexts)
            assert TASK not in json.dumps(contexts) and "plate_1" not in json.dumps(contexts)


def test_the_openpi_client_sends_the_goal_only_to_a_privileged_served_policy(catalog, tmp_path):
    sent = {}
    for name in ("random", "oracle"):
        port, record = free_port(), tmp_path / name
        record.mkdir()
        with running(helper_server("langgap-record", port, name), port, env=subprocess_env(RECORD_DIR=str(record))):
            remote = OpenpiPolicy(port=port)
            episodes(remote, catalog, PLAN[:1])
            remote.close()
        sent[name] = _recorded(record / "requests.jsonl")
    assert sent["random"] and all(r["context"]["privileged"] is None and not r["privileged"] for r in sent["random"])
    assert "(On " not in json.dumps(sent["random"])
    assert all(r["privileged"] for r in sent["oracle"])
    assert sent["oracle"][0]["context"]["privileged"]["goal"] == ["(On akita_black_bowl_1 plate_1)"]


def test_a_server_never_gives_the_goal_to_a_policy_that_is_not_privileged(catalog, tmp_path):
    log = tmp_path / "served.jsonl"
    served = ServedPolicy(ContextRecorder(str(log)), "recorder")
    full = task_context(catalog.get(TASK), catalog, init_index=0, seed=0)  # as a careless client might send
    request = {
        protocol.EPISODE_KEY: "e1",
        protocol.CONTEXT_KEY: protocol.context_to_message(full),
        protocol.STATE_KEY: np.zeros(8, dtype=np.float32),
    }
    served.infer(request)
    (context,) = _recorded(log)
    assert context["privileged"] is None and context["instruction"] == full.instruction


def test_langgap_serve_listens_on_loopback_unless_told_otherwise():
    port = free_port()
    with running(langgap_serve(port, "noop"), port) as server:
        listening = subprocess.run(["ss", "-ltnpH"], capture_output=True, text=True, check=True).stdout
    mine = [line.split()[3] for line in listening.splitlines() if f"pid={server.pid}," in line]
    assert mine == [f"127.0.0.1:{port}"]
