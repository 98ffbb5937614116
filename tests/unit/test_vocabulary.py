"""One word per verdict, defined once in `langgap.vocabulary` and shown as such by every command and report."""

from __future__ import annotations

import ast
import inspect

import pytest

import langgap.vocabulary
from langgap.catalog.task import GateResult
from langgap.cli.main import main
from langgap.validity.coverage import HEADER
from langgap.vocabulary import CEILING_TARGET, FEASIBLE_RATE, SWITCH_RATE, Verdict

# A verdict of each word, the oracle at 50/50 where the word does not rest on its rate.
VERDICTS = {
    Verdict.DOABLE: GateResult(50, 50, True, inits=50),
    Verdict.UNPROVEN: GateResult(50, 17, False, reason="oracle 17/50", inits=50),
    Verdict.INFEASIBLE: GateResult(50, 0, False, reason="oracle 0/50", inits=50, proof="Out of reach: …"),
    Verdict.UNSETTLED: GateResult(50, 50, False, reason="scene settles", inits=50),
}


def test_the_words_and_the_gates_rates():
    assert [str(v) for v in Verdict] == ["doable", "unproven", "infeasible", "unsettled"]
    assert (FEASIBLE_RATE, CEILING_TARGET, SWITCH_RATE) == (0.90, 0.95, 0.95)
    # The ground floor: every layer may import it, so it imports nothing from LangGap.
    tree = ast.parse(inspect.getsource(langgap.vocabulary))
    imported = [n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    imported += [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
    assert not [name for name in imported if name and name.split(".")[0] == "langgap"]


@pytest.mark.parametrize("word", list(Verdict))
def test_a_verdict_reads_as_its_word_wherever_it_is_shown(word):
    gate = VERDICTS[word]
    assert gate.verdict is word
    assert gate.evidence.startswith(f"{word}: ")
    others = [str(v) for v in Verdict if v is not word]
    assert not [other for other in others if other in gate.evidence]
    # beside a run's results, on init states the oracle does 1 of 2 of (⚠)
    assert gate.capped_because(1, 2).startswith(str(word))


def test_the_gate_table_counts_one_column_per_word(capsys):
    assert HEADER[4:-1] == tuple(Verdict)
    assert main(["tasks", "gate", "--catalog", "libero-pro"]) == 0
    header, *_, total = [line for line in capsys.readouterr().out.splitlines() if line.startswith(("suite", "total "))]
    assert header.split()[4:-1] == [str(v) for v in Verdict]
    # LIBERO-PRO: 114 doable, 4 unproven, none infeasible, spatial/s0's two variants unsettled
    assert total.split()[2:8] == ["120", "120", "114", "4", "0", "2"]


def test_a_task_whose_starts_do_not_come_to_rest_reads_unsettled_with_its_reason(capsys):
    """LIBERO-PRO's spatial/s0/pro-task: the oracle did it 50/50; the settle check rejected it."""
    assert main(["tasks", "show", "spatial/s0/pro-task", "--catalog", "libero-pro"]) == 0
    out = capsys.readouterr().out
    assert "gate         oracle 50/50 on init states 0–49: unsettled\n" in out
    assert "evidence:    unsettled: its starts do not come to rest (the oracle did it 50/50); the gate's reason: " \
        "scene settles\n" in out  # fmt: skip
    assert "unproven" not in out and "does not do it" not in out
    assert main(["tasks", "list", "--catalog", "libero-pro", "--tasks", "spatial/s0/*&extended"]) == 0
    listed = capsys.readouterr().out
    assert [line.split()[4] for line in listed.splitlines() if line.startswith("spatial/s0/pro-")] == ["unsettled"] * 2
    assert "2 rejected by the feasibility gate (2 unsettled)" in listed
