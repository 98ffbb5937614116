"""`experiments/small_scale_vla.sh` around its steps: which policies it runs (`CONFIGS`), and the reports it writes
from every finished run in OUT, earlier invocations' included. Every training and evaluation step is already
done here (its marker and store exist, the stores synthetic), so the script runs only `langgap report`."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests.support.harness import REPO
from tests.support.reports import memoriser, reader, write_run

SCRIPT = REPO / "experiments" / "small_scale_vla.sh"


def finished_experiment(out: Path, runs: dict[str, str]) -> Path:
    """OUT as the script leaves it after collecting, rendering and evaluating `runs` (run name -> policy)."""
    (out / "demos" / "hdf5").mkdir(parents=True)
    (out / "demos" / "collection.json").write_text("{}")
    (out / "demos" / "hdf5" / "complete").touch()
    for name, policy in runs.items():
        records = memoriser(sees_state=True, sees_goal=True) if policy == "blind" else reader()
        write_run(out / "runs" / name, policy, records)
        (out / "runs" / name / "complete").touch()
        if policy != "blind":
            (out / f"{name}.safetensors").touch()  # a trained checkpoint: the script does not train it again
    return out


def run_script(out: Path, **environment: str) -> subprocess.CompletedProcess:
    path = f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"  # this environment's `langgap`
    env = {**os.environ, "PATH": path, **environment}
    env.pop("LANGGAP_SMOKE", None)
    return subprocess.run(["bash", str(SCRIPT), str(out)], capture_output=True, text=True, cwd=REPO, env=env)


def test_each_seeds_report_compares_every_finished_policy_of_earlier_invocations_too(tmp_path):
    out = finished_experiment(
        tmp_path / "out",
        {"blind": "blind", "original": "small-vla", "extended": "small-vla", "extended-seed1": "small-vla"},
    )
    done = run_script(out, CONFIGS="extended", SEEDS="0 1")
    assert done.returncode == 0, done.stderr
    seed0 = (out / "report.md").read_text()
    # `original` ran in an earlier invocation (CONFIGS=extended now): its report keeps it, first.
    compared = [f"{out}/runs/{name}:" for name in ("original", "extended", "blind")]
    assert all(name in seed0 for name in compared), seed0[:2000]
    assert [seed0.index(name) for name in compared] == sorted(seed0.index(name) for name in compared)
    seed1 = (out / "report-seed1.md").read_text()
    assert f"{out}/runs/extended-seed1:" in seed1 and f"{out}/runs/original:" not in seed1
    pooled = (out / "pooled.md").read_text()
    rows = [line.split(" | ")[:2] for line in pooled.splitlines() if line.startswith("| ") and "Pool" not in line]
    assert rows == [["| blind", "1"], ["| original", "1"], ["| extended", "2"]]


def test_an_unknown_policy_in_configs_stops_the_script_before_anything_runs(tmp_path):
    done = run_script(tmp_path / "out", CONFIGS="original dilutd")
    assert done.returncode == 2
    assert done.stderr.startswith("error: CONFIGS: unknown policy 'dilutd'")
    assert not (tmp_path / "out").exists()
