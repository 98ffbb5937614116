"""The Ray backend on a real local Ray cluster (head + worker node), kept to loopback in its own network namespace."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tests.conftest import REPO, run_cli, store_rows

pytestmark = pytest.mark.skipif(shutil.which("unshare") is None, reason="needs unshare (util-linux) for a netns")

KEEP = ("task_id", "init_index", "seed", "condition", "success", "steps", "t0_hash", "reached", "goals_at_end")


def _in_network_namespace(script: str, ray_tmp: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    """Run a bash script in a fresh network namespace with only loopback: Ray cannot reach or bind anything else.
    Ray's session files go to `ray_tmp`, so no other Ray instance on the machine is seen or touched."""
    bin_dir = Path(sys.executable).parent
    prelude = f"""
        set -euo pipefail
        ip link set lo up
        export PATH={bin_dir}:$PATH PYTHONPATH={REPO} RAY_AUTH_MODE=disabled RAY_USAGE_STATS_ENABLED=0
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
        [*base, "--backend", "ray", "--run", str(tmp_path / "b")], capture_output=True, text=True, env=env
    )
    assert missing.returncode == 2 and "pip install 'langgap[ray]'" in missing.stderr
    assert not (tmp_path / "b").exists()


def test_shared_policy_gives_the_same_episodes(short_catalog, tmp_path):
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
    shared = tmp_path / "shared"
    result = _in_network_namespace(
        f"python -m langgap.cli.main eval {' '.join(common)} --backend ray --shared-policy --max-batch 2 "
        f"--run {shared}",
        _ray_tmp(),
    )
    assert result.returncode == 0, result.stderr
    assert [{k: r[k] for k in KEEP} for r in store_rows(shared)] == [{k: r[k] for k in KEEP} for r in store_rows(local)]
    assert all(json.loads(r["physics"]) for r in store_rows(shared))
