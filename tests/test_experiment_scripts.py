"""The experiment scripts (`experiments/small_scale.sh`, `small_scale_vla.sh`, `diversity_sweep.sh`) around their
steps: which policies they run, the settings they refuse, and the reports they write from every finished run in
OUT, earlier invocations' included. Every training and evaluation step is already done here (its marker and store
exist, the stores synthetic), so the scripts run only `langgap report` (and the sweep its table and figure)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from langgap.report.stats import wilson
from tests.support.harness import REPO
from tests.support.reports import memoriser, reader, write_run

SCRIPT = REPO / "experiments" / "small_scale_vla.sh"
SWEEP = REPO / "experiments" / "diversity_sweep.sh"


def finished_experiment(out: Path, runs: dict[str, str]) -> Path:
    """OUT as the script leaves it after collecting, rendering and evaluating `runs` (run name -> policy)."""
    (out / "demos" / "hdf5").mkdir(parents=True)
    (out / "demos" / "collection.json").write_text("{}")
    (out / "demos" / "hdf5" / "complete-96").touch()
    for name, policy in runs.items():
        records = memoriser(sees_state=True, sees_goal=True) if policy == "blind" else reader()
        write_run(out / "runs" / name, policy, records)
        (out / "runs" / name / "complete").touch()
        if policy != "blind":
            (out / f"{name}.safetensors").touch()  # a trained checkpoint: the script does not train it again
    return out


def run_script(out: Path, script: Path = SCRIPT, **environment: str) -> subprocess.CompletedProcess:
    path = f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"  # this environment's `langgap`
    env = {name: value for name, value in os.environ.items() if name != "LANGGAP_SMOKE"}  # shrunk if asked here
    env = {**env, "PATH": path, **environment}
    return subprocess.run(["bash", str(script), str(out)], capture_output=True, text=True, cwd=REPO, env=env)


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


def finished_sweep(out: Path, seeds: dict[int, str]) -> Path:
    """OUT as the sweep leaves it after K = 1 at width 64 for each seed in `seeds` (seed -> `reader` or
    `memoriser`: what its three runs hold), and `blind`."""
    (out / "demos").mkdir(parents=True)
    (out / "demos" / "collection.json").write_text("{}")
    (out / "frames.tsv").write_text("1\t95\n")
    for name in ("compositional", "novel-word", "trained"):
        write_run(out / "runs" / f"blind-{name}", "blind", memoriser(sees_state=True, sees_goal=True))
        (out / "runs" / f"blind-{name}" / "complete").touch()
    for seed, records in seeds.items():
        policy = f"k1-d64-seed{seed}" if seed else "k1-d64"
        (out / f"{policy}.safetensors").touch()  # trained: the sweep does not train it again
        for name in ("compositional", "novel-word", "trained"):
            write_run(
                out / "runs" / f"{policy}-{name}", "small-bc", {"reader": reader, "memoriser": memoriser}[records]()
            )
            (out / "runs" / f"{policy}-{name}" / "complete").touch()
    return out


def test_the_sweeps_table_counts_every_group_of_a_run_and_each_seed_beside_the_pool(tmp_path):
    out = finished_sweep(tmp_path / "out", {0: "reader", 1: "memoriser"})
    done = run_script(out, SWEEP, KS="1", WIDTHS="64", SEEDS="0 1")
    assert done.returncode == 0, done.stderr
    assert not (out / "times.tsv").exists()  # nothing collected, trained or evaluated again
    # The reader succeeds in 11 of its 12 episodes, the memoriser in 4 of 11 (one gap): the catalog's split groups
    # of a run (original, training, held-out) are counted together, never the episodes that did the original task.
    low, high = wilson(15, 23)
    cell = f"{100 * 15 / 23:.1f} [{100 * low:.1f}, {100 * high:.1f}]; 11/12, 4/11"
    rows = (out / "sweep.md").read_text().splitlines()
    assert f"| 1 | 64 | {cell} | {cell} | {cell} |" in rows
    assert "| `blind` | – | 36.4 [15.2, 64.6]; 4 of 11 |" in rows[2]
    pooled = (out / "pooled-compositional.md").read_text()
    assert "| k1-d64 | 2 |" in pooled and "| blind | 1 |" in pooled
    assert (out / "sweep.png").read_bytes()[:4] == b"\x89PNG"


def test_the_sweeps_table_and_figure_take_another_sweep_beside_it(tmp_path):
    # Two finished sweeps of K = 1 at width 64 (as if of two policies): the reader's and the memoriser's.
    one, other = finished_sweep(tmp_path / "one", {0: "reader"}), finished_sweep(tmp_path / "other", {0: "memoriser"})
    for out in (one, other):
        assert run_script(out, SWEEP, KS="1", WIDTHS="64", SEEDS="0").returncode == 0
    plot = [sys.executable, str(REPO / "experiments" / "diversity_plot.py"), str(one)]
    done = subprocess.run([*plot, "--beside", f"small-vla={other}"], capture_output=True, text=True, cwd=REPO)
    assert done.returncode == 0, done.stderr

    def cell(successes: int, episodes: int) -> str:
        low, high = wilson(successes, episodes)
        return f"{100 * successes / episodes:.1f} [{100 * low:.1f}, {100 * high:.1f}]; {successes} of {episodes}"

    rows = (one / "sweep.md").read_text().splitlines()
    reader, memoriser = cell(11, 12), cell(4, 11)
    assert rows[3:] == [f"| 1 | 64 | {reader} | {reader} | {reader} |", f"| 1 | 64, small-vla | {memoriser} | "
                        f"{memoriser} | {memoriser} |"]  # fmt: skip
    alone = subprocess.run([*plot, "--figure", str(tmp_path / "alone.png")], capture_output=True, cwd=REPO)
    assert alone.returncode == 0
    assert (one / "sweep.png").read_bytes()[:4] == b"\x89PNG"  # and the other sweep's points are drawn in it:
    assert (one / "sweep.png").read_bytes() != (tmp_path / "alone.png").read_bytes()
    labelled = subprocess.run([*plot, "--beside", f"small-vla={other}", "--label", "small-bc", "--figure",
                               str(tmp_path / "labelled.png")], cwd=REPO)  # fmt: skip
    assert labelled.returncode == 0
    assert (tmp_path / "labelled.png").read_bytes() != (one / "sweep.png").read_bytes()  # the legend names it
    refused = subprocess.run([*plot, "--beside", str(other)], capture_output=True, text=True, cwd=REPO)
    assert refused.returncode == 2
    assert f"error: --beside {other}: expected LABEL=DIR" in refused.stderr


SMALL_SCALE = REPO / "experiments" / "small_scale.sh"


@pytest.mark.parametrize(
    ("script", "setting", "message"),
    [
        (SWEEP, {"KS": "1 5"}, "KS: full-spatial-s0-compositional has no subset of '5' tasks (it has: 1 3 6 12 24)"),
        (SWEEP, {"SCENE": "goal/s8", "KS": "24"},
         "KS: full-goal-s8-compositional has no subset of '24' tasks (it has: 1 3 6 12 20)"),
        (SWEEP, {"SCENE": "object/s0"}, "SCENE: object/s0 has no shipped sweep splits (full-object-s0-compositional "
         "and full-object-s0-novel-word; docs/splits.md makes them)"),
        (SWEEP, {"WIDTHS": "64 130"}, "WIDTHS: 130 is not a multiple of the model's 4 heads"),
        (SWEEP, {"PASSES": "1.5"}, "PASSES: '1.5' is not a whole number above 0"),
        (SWEEP, {"SEEDS": "0 one"}, "SEEDS: 'one' is not a whole number"),
        (SWEEP, {"POLICY": "smolvla"}, "POLICY: 'smolvla' is neither small-bc nor small-vla"),
        (SWEEP, {"DEMOS_FROM": "nowhere"}, "DEMOS_FROM: nowhere holds no finished collection"),
        (SWEEP, {"DEVICE": "gpu"}, "DEVICE: 'gpu' is neither cpu nor cuda[:N]"),
        (SCRIPT, {"DEVICE": "cuda0"}, "DEVICE: 'cuda0' is neither cpu nor cuda[:N]"),
        (SMALL_SCALE, {"CONFIGS": "one suits"}, "CONFIGS: unknown policy 'suits' (known: original extended mixed "
         "diluted diluted-passes one original-training-vocab extended-training-vocab mixed-training-vocab "
         "diluted-training-vocab originals suites suites-originals)"),
        (SMALL_SCALE, {"ONE_DEMOS": "0"}, "ONE_DEMOS: '0' is not a whole number above 0"),
        (SMALL_SCALE, {"STEPS": "4k"}, "STEPS: '4k' is not a whole number above 0"),
        (SMALL_SCALE, {"SEEDS": "0 -1"}, "SEEDS: '-1' is not a whole number"),
    ],
    ids=lambda v: v.name if isinstance(v, Path) else None,
)  # fmt: skip
def test_a_misspelt_setting_stops_the_script_before_anything_runs(tmp_path, script, setting, message):
    done = run_script(tmp_path / "out", script, **setting)
    assert done.returncode == 2
    assert done.stderr.strip() == f"error: {message}"
    assert not (tmp_path / "out").exists()


def test_the_small_scale_reports_keep_the_scene_and_the_three_suites_apart_with_each_blind(tmp_path):
    # `one` and `originals` finished in an earlier invocation; `suites` now, on two seeds.
    out = finished_experiment(
        tmp_path / "out",
        {"blind": "blind", "blind-suites": "blind", "one": "small-bc", "originals": "small-bc",
         "suites": "small-bc", "suites-seed1": "small-bc"},
    )  # fmt: skip
    done = run_script(out, SMALL_SCALE, CONFIGS="suites", SEEDS="0 1")
    assert done.returncode == 0, done.stderr
    assert not (out / "times.tsv").exists()  # nothing collected, trained or evaluated again
    scene = (out / "report.md").read_text()
    assert f"{out}/runs/one:" in scene and f"{out}/runs/blind:" in scene and "runs/suites" not in scene
    suites = (out / "report-suites.md").read_text()
    compared = [f"{out}/runs/{name}:" for name in ("originals", "suites", "blind-suites")]
    assert all(name in suites for name in compared), suites[:2000]
    assert [suites.index(name) for name in compared] == sorted(suites.index(name) for name in compared)
    assert f"{out}/runs/one:" not in suites
    seed1 = (out / "report-suites-seed1.md").read_text()
    assert f"{out}/runs/suites-seed1:" in seed1 and f"{out}/runs/originals:" not in seed1
    assert not (out / "report-seed1.md").exists()  # no scene policy finished on seed 1

    def pools(name: str) -> list[list[str]]:
        lines = (out / name).read_text().splitlines()
        return [line.split(" | ")[:2] for line in lines if line.startswith("| ") and "Pool" not in line]

    assert pools("pooled.md") == [["| blind", "1"], ["| one", "1"]]
    assert pools("pooled-suites.md") == [["| blind", "1"], ["| originals", "1"], ["| suites", "2"]]


def test_a_training_vocab_row_trains_its_policy_with_the_training_datas_words_on_the_same_data(tmp_path):
    """`mixed-training-vocab` is `mixed` with `--vocabulary training`: same demonstrations and tasks, and the
    checkpoint says which vocabulary it has (a real run, shrunk by LANGGAP_SMOKE)."""
    import json

    from safetensors import safe_open

    out = tmp_path / "out"
    done = run_script(out, SMALL_SCALE, CONFIGS="mixed-training-vocab mixed", LANGGAP_SMOKE="1")
    assert done.returncode == 0, done.stderr[-3000:]

    def training(name: str) -> dict:
        with safe_open(str(out / f"{name}.safetensors"), "np") as checkpoint:
            return json.loads(checkpoint.metadata()["training"])

    ab, mixed = training("mixed-training-vocab"), training("mixed")
    assert (ab["vocabulary"], mixed["vocabulary"]) == ("training", "catalogs")
    assert (ab["data"], ab["tasks"], ab["demos"], ab["seed"]) == (mixed["data"], mixed["tasks"], mixed["demos"], 0)
    assert f"{out}/runs/mixed-training-vocab:" in (out / "report.md").read_text()
    assert "| mixed-training-vocab | 1 |" in (out / "pooled.md").read_text()


def test_a_render_at_another_size_is_not_taken_for_the_finished_one(tmp_path):
    # OUT holds a finished 96 px render (and every run): asked for 64 px, the script renders again, and this
    # collection (an empty manifest) cannot be rendered, so it stops there, before training or evaluating.
    out = finished_experiment(tmp_path / "out", {"blind": "blind", "extended": "small-vla"})
    done = run_script(out, CONFIGS="extended", SEEDS="0", SIZE="64")
    assert done.returncode != 0
    assert "is not a collection's manifest" in done.stderr, done.stderr
    assert not (out / "demos" / "hdf5" / "complete-64").exists()
    assert run_script(out, CONFIGS="extended", SEEDS="0").returncode == 0  # at 96 px nothing is rendered again


def test_the_sweeps_device_reaches_its_training(tmp_path):
    # K = 1's checkpoint is missing, so the sweep trains it, on a device no machine has: `langgap train` refuses
    # it by name before reading the demonstrations (which this OUT does not hold).
    out = finished_sweep(tmp_path / "out", {0: "reader"})
    (out / "k1-d64.safetensors").unlink()
    done = run_script(out, SWEEP, KS="1", WIDTHS="64", SEEDS="0", DEVICE="cuda:99")
    assert done.returncode != 0
    assert "error: --device cuda:99: PyTorch sees" in done.stderr, done.stderr
    assert not (out / "k1-d64.safetensors").exists()


def test_the_sweep_with_small_vla_renders_its_collection_before_training_and_only_then(tmp_path):
    # Every run of K = 1 is finished and no render is marked. With its checkpoint there (trained elsewhere, e.g.
    # on a GPU machine), small-vla's sweep renders nothing: it only evaluates and writes its tables.
    out = finished_sweep(tmp_path / "out", {0: "reader"})
    done = run_script(out, SWEEP, POLICY="small-vla", KS="1", WIDTHS="64", SEEDS="0")
    assert done.returncode == 0, done.stderr
    assert not (out / "times.tsv").exists()
    # Without it, the sweep renders before training (the shared `images` of experiments/images.sh), and this
    # collection (an empty manifest) cannot be rendered, so it stops there.
    (out / "k1-d64.safetensors").unlink()
    done = run_script(out, SWEEP, POLICY="small-vla", KS="1", WIDTHS="64", SEEDS="0")
    assert done.returncode != 0
    assert "is not a collection's manifest" in done.stderr, done.stderr
    assert not (out / "k1-d64.safetensors").exists()
