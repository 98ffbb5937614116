"""Replicate runs pooled (`langgap report --pool`), on synthetic stores: counts summed, each run's beside them."""

from __future__ import annotations

import csv
import io
import json

import pytest

from langgap.cli.main import main
from langgap.errors import LangGapError
from langgap.report import pooled_text
from langgap.report.pooled import pool, replicate_tests
from langgap.report.stats import wilson
from tests.support.reports import memoriser, reader, write_run


@pytest.fixture
def replicates(tmp_path):
    """Two runs of `my-vla` (one memorises, one reads) and one of `blind`."""
    return {
        "memorising": write_run(tmp_path / "seed0", "my-vla", memoriser()),
        "reading": write_run(tmp_path / "seed1", "my-vla", reader()),
        "blind": write_run(tmp_path / "blind", "blind", memoriser(sees_state=True, sees_goal=True)),
    }


def test_a_pool_counts_its_runs_episodes_together_and_keeps_each_runs(replicates):
    rows = pool({"vla": [replicates["memorising"], replicates["reading"]], "blind": [replicates["blind"]]})
    assert [row.label for row in rows] == ["vla", "blind"]
    vla = rows[0]
    assert [c.group for c in vla.cells] == ["original", "train", "heldout", "did_source_task"]
    figures = {c.group: (c.pooled.successes, c.pooled.episodes, c.pooled.gaps, c.counts) for c in vla.cells}
    assert figures == {
        "original": (8, 8, 0, "4, 4 of 4"),
        "train": (4, 8, 0, "0, 4 of 4"),
        "heldout": (3, 7, 1, "0/3, 3/4"),  # the memoriser's gap is left out of the rate, counted beside it
        "did_source_task": (7, 15, 1, "7/7, 0/8"),
    }
    assert vla.cell("train").pooled.ci == wilson(4, 8)


def test_the_table_shows_pooled_rates_with_intervals_and_each_runs_successes(replicates):
    text = pooled_text({"vla": [replicates["memorising"], replicates["reading"]]})
    row = next(line for line in text.splitlines() if line.startswith("| vla"))
    low, high = wilson(4, 8)
    assert row.split(" | ")[1:4] == [
        "2",
        "100.0 [67.6, 100.0]; 4, 4 of 4",
        f"50.0 [{100 * low:.1f}, {100 * high:.1f}]; 0, 4 of 4",
    ]
    assert "42.9 [15.8, 75.0] (1 gaps); 0/3, 3/4" in row


def test_json_and_csv_hold_the_same_counts(replicates):
    pools = {"vla": [replicates["memorising"], replicates["reading"]]}
    data = json.loads(pooled_text(pools, "json"))
    train = next(c for c in data["pools"][0]["cells"] if c["group"] == "train")
    assert train["pooled"]["successes"] == 4 and [r["successes"] for r in train["replicates"]] == [0, 4]
    rows = [r for r in csv.DictReader(io.StringIO(pooled_text(pools, "csv"))) if r["group"] == "train"]
    assert [(r["run"], r["successes"]) for r in rows] == [
        (str(replicates["memorising"]), "0"),
        (str(replicates["reading"]), "4"),
        ("pooled", "4"),
    ]


def test_pools_of_several_runs_are_compared_over_their_runs(replicates, tmp_path):
    pools = {
        "memorising": [replicates["memorising"], write_run(tmp_path / "m1", "my-vla", memoriser())],
        "reading": [replicates["reading"], write_run(tmp_path / "r1", "my-vla", reader())],
        "blind": [replicates["blind"]],  # one run: no spread to test against
    }
    tests = replicate_tests(pool(pools))
    # The original task: every run of both pools at 100 %, nothing to test.
    assert [(t.first, t.second, t.group) for t in tests] == [
        ("memorising", "reading", "train"),
        ("memorising", "reading", "heldout"),
        ("memorising", "reading", "did_source_task"),
    ]
    train = tests[0]
    assert (train.first_rates, train.second_rates, train.difference) == ((0.0, 0.0), (1.0, 1.0), 1.0)
    # 2 of the C(4, 2) = 6 ways to split four runs in two are as far apart: two runs a side can give no less.
    assert train.p == pytest.approx(1 / 3) and train.floor == pytest.approx(1 / 3)
    text = pooled_text(pools)
    assert "### Between pools over their runs" in text
    assert (
        "| memorising vs reading | Extended, training split | 0.0, 0.0 | 100.0, 100.0 | +100.0 (reading minus "
        "memorising) | 0.333 | 0.333 |" in text
    )
    assert "Difference of means (points, second minus first)" in text  # the column says which side minus which
    swapped = pooled_text({"reading": pools["reading"], "memorising": pools["memorising"]})
    assert "| -100.0 (memorising minus reading) |" in swapped
    data = json.loads(pooled_text(pools, "json"))
    assert [row["label"] for row in data["pools"]] == ["memorising", "reading", "blind"]
    assert [t["group"] for t in data["tests"]] == ["train", "heldout", "did_source_task"]
    alone = pooled_text({"memorising": pools["memorising"], "blind": pools["blind"]})
    assert "Between pools" not in alone  # one pool with several runs: nothing to compare


def test_a_pool_is_one_configuration_on_one_protocol(replicates, tmp_path):
    with pytest.raises(LangGapError, match="mixes policies"):
        pool({"x": [replicates["memorising"], replicates["blind"]]})
    with pytest.raises(LangGapError, match="names a run twice"):
        pool({"x": [replicates["reading"], replicates["reading"]]})
    other = write_run(tmp_path / "other", "my-vla", reader(), physics={"mujoco": "3.3.0"})
    with pytest.raises(LangGapError, match="differs .* in physics"):
        pool({"x": [replicates["reading"]], "y": [other]})  # across pools too: one table, one protocol
    assert pool({"x": [replicates["reading"], other]}, allow_mismatch=True)[0].cell("original").pooled.episodes == 8


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--pool", "x"], "--pool takes LABEL=RUN,RUN..."),
        (["--pool", "x={reading}", "--pool", "x={memorising}"], "--pool 'x' is given twice"),
        (["{reading}", "--pool", "x={memorising}"], "without RUN"),
        (["--pool", "x={reading}", "--summary"], "without --summary"),
        (["--pool", "x={reading}", "--no-published"], "without --no-published"),
        ([], "name a run directory"),
    ],
)
def test_the_cli_refuses_what_a_pooled_report_cannot_show(argv, message, replicates, capsys):
    assert main(["report", *(a.format(**replicates) for a in argv)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and message in err[0]


def test_the_cli_prints_the_pooled_table_in_the_format_asked(replicates, capsys):
    pools = ["--pool", f"vla={replicates['memorising']},{replicates['reading']}", "--pool", f"b={replicates['blind']}"]
    assert main(["report", *pools]) == 0
    text = capsys.readouterr().out
    assert text.startswith("### Pooled over replicate runs") and "| vla | 2 |" in text and "| b | 1 |" in text
    assert main(["report", *pools, "--format", "latex"]) == 0
    assert capsys.readouterr().out.startswith(r"\begin{table}")
