"""The Ray backend on a real local Ray cluster (head + worker node), kept to loopback in its own network namespace."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from tests.support.harness import REPO, TINY_TASK, run_cli, store_rows

pytestmark = pytest.mark.requires(shutil.which("unshare") is not None, "unshare (util-linux) for a network namespace")

KEEP = (
    "task_id", "init_index", "seed", "condition", "success", "steps", "t0_hash", "reached", "goals_at_end",
    "instructions",
)  # fmt: skip


# A network inside the namespace: a non-loopback address with a default route, as on a real
# machine, so a server that binds "the machine's address" or every interface shows it.
_FAKE_NETWORK = """
        ip link add lg0 type veth peer name lg1
        ip addr add 10.77.0.1/24 dev lg0
        ip link set lg0 up
        ip link set lg1 up
        ip route add default via 10.77.0.2 dev lg0
"""


def _in_network_namespace(
    script: str, ray_tmp: Path, timeout: float = 600, *, network: bool = False
) -> subprocess.CompletedProcess:
    """Run a bash script in a fresh network namespace (loopback only, or with `network` a private
    non-loopback address too): nothing started inside can reach or be reached from outside.
    Ray's session files go to `ray_tmp`, so no other Ray instance on the machine is seen or touched."""
    bin_dir = Path(sys.executable).parent
    prelude = f"""
        set -euo pipefail
        ip link set lo up
        {_FAKE_NETWORK if network else ""}
        export PATH={bin_dir}:$PATH PYTHONPATH={REPO / "src"}:{REPO} RAY_AUTH_MODE=disabled RAY_USAGE_STATS_ENABLED=0
        export RAY_TMPDIR={ray_tmp}
        trap 'ray stop --force >/dev/null 2>&1 || true' EXIT
    """
    return subprocess.run(
        ["unshare", "-n", "bash", "-c", textwrap.dedent(prelude) + textwrap.dedent(script)],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def _ray_tmp() -> Path:
    # Ray's socket paths must stay short (Unix sockets allow ~107 bytes), so not pytest's deep tmp_path.
    import tempfile

    return Path(tempfile.mkdtemp(prefix="lg-ray-", dir="/tmp"))


@pytest.fixture(scope="module")
def reference_episodes(short_catalog, tmp_path_factory):
    """The plan of `_POOL_RUN` run in this process: what every pool must reproduce."""
    run = tmp_path_factory.mktemp("reference") / "run"
    assert run_cli("eval", *_POOL_RUN, short_catalog, "--workers", "0", "--run", str(run)).returncode == 0
    return [{k: r[k] for k in (*KEEP, "outcome", "instruction")} for r in store_rows(run)]


_POOL_RUN = (
    "--policy",
    "random",
    "--episodes",
    "2",
    "--condition",
    "given",
    "--condition",
    "shuffled",
    "--condition",
    "switch:5",  # the instruction changes mid-episode: its timeline is the same on every pool
    "--condition",
    "nonsense",
    "--no-progress",
    "--quiet",
    "--catalog",
)


@pytest.mark.parametrize(
    "pool", ["in-process", "processes", "ray", "processes --share-rollouts", "ray --share-rollouts"]
)
def test_the_same_plan_gives_the_same_episodes_on_every_pool(pool, reference_episodes, short_catalog, tmp_path):
    """Shared rollouts too (`random` is instruction-blind: per init state, one rollout for every task and
    condition but the switch, and one for the switch:5 episodes, which share theirs) give the episodes of the
    reference, run one by one."""
    run = tmp_path / "run"
    pool, _, sharing = pool.partition(" ")
    args = [*_POOL_RUN, short_catalog, "--run", str(run), *([sharing] if sharing else [])]
    if pool == "ray":
        command = " ".join(["python -m langgap.cli.main eval", *args, "--backend ray --workers 2"])
        result = _in_network_namespace(command, _ray_tmp())
    else:
        result = run_cli("eval", *args, "--workers", "0" if pool == "in-process" else "2")
    assert result.returncode == 0, result.stderr
    assert ("shared rollouts: 24 episodes in 4 rollouts" in result.stdout) == bool(sharing)
    rows = store_rows(run)
    assert [{k: r[k] for k in reference_episodes[0]} for r in rows] == reference_episodes
    assert {r["worker"] for r in rows} == ({0} if pool == "in-process" else {0, 1})


def test_cluster_run_survives_a_killed_worker_and_equals_the_local_backend(short_catalog, tmp_path):
    common = ["--policy", "random", "--catalog", short_catalog, "--episodes", "4", "--no-progress", "--quiet"]
    local = tmp_path / "local"
    assert run_cli("eval", *common, "--workers", "2", "--run", str(local)).returncode == 0
    ray_run = tmp_path / "ray"
    args = " ".join(
        common + ["--workers", "2", "--backend", "ray", "--ray-address", "127.0.0.1:6399", "--run", str(ray_run)]
    )
    count_rows = (
        f"import sqlite3; print(sqlite3.connect('{ray_run}/episodes.sqlite')"
        ".execute('select count(*) from episodes').fetchone()[0])"
    )
    result = _in_network_namespace(
        f"""
        ray start --head --port 6399 --num-cpus 1 --include-dashboard false --temp-dir "$RAY_TMPDIR" > /dev/null
        ray start --address 127.0.0.1:6399 --num-cpus 1 > /dev/null
        python -m langgap.cli.main eval {args} &
        EVAL=$!
        # Once episodes flow, kill one actor's process mid-run.
        for _ in $(seq 1 240); do
            [ "$(python -c "{count_rows}" 2>/dev/null || echo 0)" -ge 2 ] && break
            sleep 0.5
        done
        VICTIM=$(pgrep -f -o '^ray::RunnerActor')
        kill -9 "$VICTIM"
        echo "killed actor process $VICTIM"
        wait $EVAL
    """,
        _ray_tmp(),
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "killed actor process" in result.stdout
    rows = store_rows(ray_run)
    assert len(rows) == 12 and all(r["status"] == "done" for r in rows)
    assert [{k: r[k] for k in KEEP} for r in rows] == [{k: r[k] for k in KEEP} for r in store_rows(local)]
    assert any(r["attempts"] == 2 for r in rows)  # the killed actor's episode ran again elsewhere
    # A resumed run is the same run, whichever backend made it.
    resumed = run_cli("eval", *common, "--workers", "1", "--run", str(ray_run), "--resume")
    assert resumed.returncode == 0 and "12 already stored, 0 run" in resumed.stdout


def test_local_ray_instance_when_no_address_is_given(short_catalog, tmp_path):
    run = tmp_path / "run"
    result = _in_network_namespace(
        f"""
        python -m langgap.cli.main eval --policy noop --catalog {short_catalog} --episodes 1 --workers 2 \
            --backend ray --run {run} --no-progress --quiet
    """,
        _ray_tmp(),
    )
    assert result.returncode == 0, result.stderr
    assert len(store_rows(run)) == 3


def test_a_validation_starts_one_local_ray_instance_for_all_its_parts(short_catalog):
    """The gate's episodes and its settle probes (and searches) run on one local Ray instance, not one each:
    Ray writes a session directory per instance it starts."""
    ray_tmp = _ray_tmp()
    result = _in_network_namespace(
        f"""
        python -m langgap.cli.main validate --catalog {short_catalog} --inits 1 --workers 1 --backend ray \
            --search-budget 0 --no-progress || test $? -eq 1
    """,
        ray_tmp,
    )
    assert result.returncode == 0, result.stderr
    assert "spatial/s0/" in result.stdout  # its rows: the episodes ran
    assert len(list((ray_tmp / "ray").glob("session_2*"))) == 1


def test_core_works_without_ray(short_catalog, tmp_path):
    block_ray = "import sys; sys.modules['ray'] = None; from langgap.cli.main import main; sys.exit(main(sys.argv[1:]))"
    base = [
        sys.executable,
        "-c",
        block_ray,
        "eval",
        "--policy",
        "noop",
        "--catalog",
        short_catalog,
        "--episodes",
        "1",
        "--no-progress",
        "--quiet",
        "--workers",
        "0",
    ]
    env = {"PYTHONPATH": str(REPO), "PATH": str(Path(sys.executable).parent)}
    local = subprocess.run([*base, "--run", str(tmp_path / "a")], capture_output=True, text=True, env=env)
    assert local.returncode == 0, local.stderr
    missing = subprocess.run(
        [*base, "--backend", "ray", "--workers", "1", "--run", str(tmp_path / "b")],
        capture_output=True,
        text=True,
        env=env,
    )
    assert missing.returncode == 2 and "pip install 'langgap[ray]'" in missing.stderr
    assert not (tmp_path / "b").exists()


def test_shared_policy_batches_queries_and_gives_the_same_episodes(short_catalog, tmp_path):
    common = [
        "--policy",
        "random",
        "--policy-arg",
        "chunk=3",
        "--catalog",
        short_catalog,
        "--episodes",
        "2",
        "--no-progress",
        "--quiet",
        "--workers",
        "2",
    ]
    local = tmp_path / "local"
    assert run_cli("eval", *common, "--run", str(local)).returncode == 0
    shared, unbatched = tmp_path / "shared", tmp_path / "unbatched"
    eval_ray = f"python -m langgap.cli.main eval {' '.join(common)} --backend ray --shared-policy --max-wait-ms 300"
    result = _in_network_namespace(
        f"{eval_ray} --max-batch 2 --run {shared}\n{eval_ray} --max-batch 1 --run {unbatched}", _ray_tmp()
    )
    assert result.returncode == 0, result.stderr
    (queries, calls), (queries_1, calls_1) = [
        tuple(map(int, m)) for m in re.findall(r"shared policy: (\d+) queries in (\d+) batched calls", result.stdout)
    ]
    assert queries == queries_1 > 0
    assert calls < queries  # two environment actors' queries shared forward passes
    assert calls_1 == queries_1  # --max-batch 1: one query per call
    assert [{k: r[k] for k in KEEP} for r in store_rows(shared)] == [{k: r[k] for k in KEEP} for r in store_rows(local)]
    assert all(json.loads(r["physics"]) for r in store_rows(shared))


def test_policy_gpus_beyond_the_cluster_is_an_error_before_anything_is_stored(short_catalog, tmp_path):
    run = tmp_path / "run"
    result = _in_network_namespace(
        f"python -m langgap.cli.main eval --policy noop --catalog {short_catalog} --episodes 1 --backend ray "
        f"--shared-policy --policy-gpus 1 --run {run} --no-progress --quiet",
        _ray_tmp(),
    )
    assert result.returncode == 2
    assert result.stderr.strip().splitlines()[-1] == "error: --policy-gpus 1: the Ray cluster has 0 GPU(s)"
    assert not run.exists()


@pytest.mark.parametrize("address", ["127.0.0.1:1", "no-such-head.invalid:6379"])
def test_a_ray_address_nothing_answers_on_is_one_error_line_in_seconds(address, short_catalog, tmp_path):
    """Ray's own connect waits for minutes on a dead or misspelled head (seen: over ten); the command says so now."""
    run = tmp_path / "run"
    started = time.monotonic()
    result = run_cli("eval", "--policy", "noop", "--catalog", short_catalog, "--episodes", "1", "--backend", "ray",
                     "--ray-address", address, "--run", str(run), "--no-progress", "--quiet", timeout=120)  # fmt: skip
    assert time.monotonic() - started < 60
    assert result.returncode == 2
    assert result.stderr.strip().splitlines()[-1].startswith(f"error: cannot reach the Ray cluster at {address}: ")
    assert not (run / "episodes.sqlite").exists()


def test_a_local_ray_instance_listens_on_loopback_only(short_catalog, tmp_path):
    run = tmp_path / "run"
    result = _in_network_namespace(
        f"""
        python -m langgap.cli.main eval --policy delay --policy-arg delay_ms=100 --catalog {short_catalog} \
            --episodes 1 --workers 2 --backend ray --run {run} --no-progress --quiet &
        EVAL=$!
        # Once an environment actor runs an episode, every Ray process has started its servers.
        for _ in $(seq 1 240); do
            [ "$(pgrep -fc '^ray::RunnerActor' || true)" -ge 1 ] && break
            sleep 0.5
        done
        ss -ltnpH
        wait $EVAL
    """,
        _ray_tmp(),
        network=True,
    )
    assert result.returncode == 0, result.stderr
    listening = [line.split()[3] for line in result.stdout.splitlines() if line.startswith("LISTEN")]
    owners = " ".join(line for line in result.stdout.splitlines() if line.startswith("LISTEN"))
    assert "gcs_server" in owners and "raylet" in owners and "ray::RunnerActo" in owners  # ss cuts names at 15
    exposed = [a for a in listening if a.rsplit(":", 1)[0] not in ("127.0.0.1", "[::ffff:127.0.0.1]", "[::1]")]
    assert not exposed, result.stdout
    assert len(store_rows(run)) == 3


def test_every_kind_of_work_runs_on_a_worker_node_that_sees_another_disk(short_catalog, tiny_collection, tmp_path):
    """eval --video, collect and validate on a two-node cluster whose only worker node has its own disk at the
    output directory (a tmpfs mounted there in its mount namespace): what the driver finds there, it wrote
    from what the actors sent back; and the results are those of a local run."""
    out = tmp_path / "out"
    out.mkdir()
    cluster = "--backend ray --ray-address 127.0.0.1:6399 --no-progress"
    local_gate = tmp_path / "local-gate.json"
    gate = ["validate", "--catalog", short_catalog, "--inits", "1", "--search-budget", "1", "--no-progress"]
    assert run_cli(*gate, "--workers", "0", "--out", str(local_gate)).returncode == 1  # 15 steps: all rejected
    result = _in_network_namespace(
        f"""
        ray start --head --port 6399 --num-cpus 0 --include-dashboard false --temp-dir "$RAY_TMPDIR" > /dev/null
        unshare -m bash -c 'mount -t tmpfs tmpfs {out} && ray start --address 127.0.0.1:6399 --num-cpus 2 > /dev/null'
        python -m langgap.cli.main eval --policy noop --catalog {short_catalog} --episodes 1 --video first:1 \
            --quiet --workers 2 --run {out}/eval {cluster}
        python -m langgap.cli.main collect --tasks {TINY_TASK} --demos 2 --seed 7 --noise 0.2 --format compact \
            --out {out}/demos --workers 1 {cluster}
        python -m langgap.cli.main {" ".join(gate)} --out {out}/gate.json --workers 2 {cluster} || echo "gate: $?"
    """,
        _ray_tmp(),
    )
    assert result.returncode == 0, result.stdout + result.stderr
    filmed = [r for r in store_rows(out / "eval") if r["video"]]
    assert len(filmed) == 1 and (out / "eval" / filmed[0]["video"]).stat().st_size > 1000
    assert "gate: 1" in result.stdout  # rejected, as locally
    ray_gate, here = json.loads((out / "gate.json").read_text()), json.loads(local_gate.read_text())
    assert ray_gate == here
    from langgap.demos.compact import demo_files, load_demo

    assert [p.relative_to(out / "demos") for p in demo_files(out / "demos")] == [
        p.relative_to(tiny_collection) for p in demo_files(tiny_collection)
    ]
    for a, b in zip(demo_files(out / "demos"), demo_files(tiny_collection), strict=True):
        assert (load_demo(a).actions == load_demo(b).actions).all()
