"""The local backend's shared policy (`--backend local --shared-policy`): real LIBERO episodes on worker
processes, one real policy process batching their queries over its Unix socket."""

from __future__ import annotations

import os
import re
import signal
import sqlite3
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from tests.support.harness import REPO, run_cli, store_rows
from tests.test_ray import KEEP

SUMMARY = re.compile(r"shared policy: (\d+) queries in (\d+) batched calls")


def _eval(short_catalog: str, run: Path, *extra: str) -> subprocess.CompletedProcess:
    return run_cli(
        "eval", "--catalog", short_catalog, "--episodes", "2", "--workers", "2", "--no-progress", "--quiet",
        "--run", str(run), *extra,
    )  # fmt: skip


def _episodes(run: Path) -> list[dict]:
    return [{k: r[k] for k in KEEP} for r in store_rows(run)]


def test_two_workers_sharing_one_batching_policy_give_the_episodes_of_unshared_workers(short_catalog, tmp_path):
    def recorder(log: str) -> list[str]:
        return ["--policy", "tests.support.policies:BatchRecorder", "--policy-arg", f"path={tmp_path / log}"]

    two_tasks = ["--tasks", "spatial/s0/black-bowl-*"]
    own = _eval(short_catalog, tmp_path / "own", *recorder("own.log"), *two_tasks)
    assert own.returncode == 0, own.stderr
    own_rows = store_rows(tmp_path / "own")
    assert len({r["policy_config_hash"] for r in own_rows}) == 1
    counted = {}
    for max_batch in (2, 1):
        run = tmp_path / f"shared-{max_batch}"
        result = _eval(
            short_catalog, run, *recorder(f"{max_batch}.log"), *two_tasks,
            "--shared-policy", "--max-batch", str(max_batch), "--max-wait-ms", "300",
        )  # fmt: skip
        assert result.returncode == 0, result.stderr
        assert _episodes(run) == _episodes(tmp_path / "own")
        # The same policy, the same provenance: batching settings are not part of the policy's config.
        assert {r["policy_config_hash"] for r in store_rows(run)} == {r["policy_config_hash"] for r in own_rows}
        assert {r["worker"] for r in store_rows(run)} == {0, 1}
        queries, calls = map(int, SUMMARY.search(result.stdout).groups())
        sizes = [int(n) for n in (tmp_path / f"{max_batch}.log").read_text().split()]  # act_batch's log
        assert (len(sizes), sum(sizes), max(sizes)) == (calls, queries, max_batch)
        assert queries == sum(r["policy_calls"] for r in store_rows(run))
        counted[max_batch] = queries, calls
    (queries, calls), (queries_1, calls_1) = counted[2], counted[1]
    assert queries == queries_1 > 0
    assert calls < queries  # the two workers' queries shared forward passes
    assert calls_1 == queries_1  # --max-batch 1: one query per call
    assert not (tmp_path / "own.log").exists()  # unshared workers never batch


def _tree(root: int) -> set[int]:
    """`root` and every live process below it."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            state, parent = stat.read_text().rsplit(")", 1)[1].split()[:2]
        except OSError:
            continue
        if state != "Z":
            children.setdefault(int(parent), []).append(int(stat.parent.name))
    tree, todo = set(), [root]
    while todo:
        pid = todo.pop()
        tree.add(pid)
        todo.extend(children.get(pid, []))
    return tree


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def _listening(options: str) -> list[tuple[str, set[int]]]:
    """Every listening socket `ss` shows (`-x` Unix, `-tu` TCP and UDP): its address and its processes."""
    lines = subprocess.run(["ss", f"-l{options}pnH"], capture_output=True, text=True, check=True).stdout.splitlines()
    return [(line.split()[4], {int(p) for p in re.findall(r"pid=(\d+)", line)}) for line in lines]


def _policy_process(socket_dir: Path, timeout: float = 180) -> int:
    """The process listening on a shared policy socket under `socket_dir` (waits for it to appear)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for address, pids in _listening("x"):
            if address.startswith(f"{socket_dir}/langgap-policy-") and pids:
                return min(pids)
        time.sleep(0.2)
    raise AssertionError(f"no shared policy socket appeared under {socket_dir}")


def _episodes_stored(run: Path) -> bool:
    """True once a run store holds an episode row (the file exists a moment before its tables)."""
    if not (run / "episodes.sqlite").exists():  # checked first: connecting would create the file
        return False
    try:
        return bool(store_rows(run))
    except sqlite3.OperationalError:  # no table yet
        return False


def test_the_policy_process_listens_on_no_network_and_ends_with_the_run_even_a_killed_one(short_catalog, tmp_path):
    # The socket's directory goes under a short private TMPDIR (Unix socket paths allow ~107 bytes).
    sockets = Path(tempfile.mkdtemp(prefix="lg-", dir="/tmp"))
    run = tmp_path / "run"
    command = [
        sys.executable, "-m", "langgap.cli.main", "eval", "--policy", "delay", "--policy-arg", "delay_ms=50",
        "--catalog", short_catalog, "--episodes", "2", "--workers", "2", "--shared-policy", "--no-progress",
        "--quiet", "--run", str(run), "--resume",
    ]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(REPO / "src") + os.pathsep + str(REPO), "TMPDIR": str(sockets)}
    first = subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    policy = _policy_process(sockets)
    deadline = time.monotonic() + 180
    while not _episodes_stored(run):
        assert time.monotonic() < deadline and first.poll() is None
        time.sleep(0.2)
    tree = _tree(first.pid)
    assert policy in tree and len(tree) >= 4  # langgap eval, its policy process and two workers (at least)
    assert not [address for address, pids in _listening("tu") if pids & tree]  # no TCP or UDP listener
    first.send_signal(signal.SIGKILL)
    first.wait()
    deadline = time.monotonic() + 10
    while any(map(_alive, tree)) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not [pid for pid in tree if _alive(pid)]  # no orphan: neither the policy process nor a worker
    assert not list(sockets.iterdir())  # and its socket is removed
    # A resumed run starts its own policy process, which ends with the run.
    second = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    policy = _policy_process(sockets)
    out, err = second.communicate(timeout=600)
    assert second.returncode == 0, err
    assert SUMMARY.search(out) and int(re.search(r"(\d+) already stored", out).group(1)) >= 1
    assert not _alive(policy) and not list(sockets.iterdir())
    assert len(store_rows(run)) == 6 and {r["status"] for r in store_rows(run)} == {"done"}
    sockets.rmdir()


def test_a_crashed_policy_process_stops_the_run_with_no_verdict_and_resume_continues(short_catalog, tmp_path):
    run = tmp_path / "run"
    crash_once = ["--policy", "tests.support.policies:CrashOncePolicy", "--policy-arg", f"marker_dir={tmp_path}"]
    stopped = _eval(short_catalog, run, *crash_once, "--shared-policy")
    assert stopped.returncode == 4, stopped.stderr
    assert (
        stopped.stderr.strip()
        .splitlines()[-1]
        .startswith(
            "error: stopped after 3 episodes in a row failed with: PolicyServerError: the shared policy process is gone"
        )
    )
    assert (tmp_path / "crashed").exists()  # it was the policy process that died
    assert store_rows(run) == []  # no gap, no verdict charged to the policy
    resumed = _eval(short_catalog, run, *crash_once, "--shared-policy", "--resume")
    assert resumed.returncode == 0, resumed.stderr
    rows = store_rows(run)
    assert len(rows) == 6 and all(r["status"] == "done" and r["outcome"] != "policy_error" for r in rows)
