"""LangGap's words, defined once in `langgap.vocabulary`: one word per verdict, shown as such by every command and
report; the kinds of task, conditions, outcomes, steppings and seed schemes, the strings stored before they were
enumerations, compared as members and kept plain wherever a member's repr would show."""

from __future__ import annotations

import argparse
import ast
import inspect
from pathlib import Path

import pytest

import langgap.vocabulary
from langgap import stack
from langgap.catalog.verdicts import GateResult
from langgap.cli.main import build_parser, main
from langgap.engine.spec import RunSpec
from langgap.gate.coverage import HEADER
from langgap.vocabulary import (
    BEYOND_DIMENSIONS,
    CEILING_TARGET,
    EXTERNAL_DIMENSIONS,
    FEASIBLE_RATE,
    PAPER_DIMENSIONS,
    SWITCH_RATE,
    Condition,
    Dimension,
    InstructionStyle,
    Outcome,
    SeedScheme,
    Split,
    Stepping,
    TaskKind,
    Verdict,
    switch_step,
)
from tests.support.harness import cli_parsers

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


def test_the_core_words_are_the_strings_registries_and_stores_hold():
    assert [str(k) for k in TaskKind] == ["original", "extended"]
    assert [str(c) for c in Condition] == ["given", "empty", "shuffled", "source", "nonsense"]
    conditions = ("switch:5", "switch:1", "switch:0", "switch:x", "given")
    assert [switch_step(c) for c in conditions] == [5, 1, None, None, None]
    assert [str(o) for o in Outcome] == [
        "success", "persisted", "wrong_order", "did_source_task", "did_other_task", "no_goal_reached",
        "policy_error", "gap",
    ]  # fmt: skip
    assert [str(s) for s in Stepping] == ["exact", "fast", "robosuite"]
    assert [str(s) for s in SeedScheme] == ["per-episode", "openpi"]
    assert [str(s) for s in Split] == ["original", "train", "heldout"]
    assert [str(s) for s in InstructionStyle] == ["libero", "paper", "package"]
    # an original's dimension is its kind's word; the others fall in three groups, each once
    groups = (PAPER_DIMENSIONS, BEYOND_DIMENSIONS, EXTERNAL_DIMENSIONS)
    assert [Dimension.ORIGINAL, *(d for group in groups for d in group)] == list(Dimension)
    assert [str(d) for d in PAPER_DIMENSIONS] == [
        "change_object",
        "change_target",
        "spatial_description",
        "drawer_action",
    ]
    assert Dimension.ORIGINAL == Split.ORIGINAL == TaskKind.ORIGINAL


_ENUMS = (TaskKind, Condition, Outcome, Stepping, SeedScheme, Dimension, Split, InstructionStyle)
_WORDS = {str(w) for words in _ENUMS for w in words}
# Fields whose own words share a core word's string: an `Origin`'s `init_runs` is `own` or `source` (its file).
_OTHER_WORDS = {"init_runs"}


def _field(node: ast.expr) -> str | None:
    return node.attr if isinstance(node, ast.Attribute) else node.id if isinstance(node, ast.Name) else None


def _literal_words(node: ast.expr) -> set[str]:
    """The words written as strings in `node`: a string, or a collection of strings that are all words (one that
    holds other strings too, `("train", "eval")`, is a set of keys of its own)."""
    items = node.elts if isinstance(node, ast.Tuple | ast.List | ast.Set) else [node]
    strings = {i.value for i in items if isinstance(i, ast.Constant) and isinstance(i.value, str)}
    return strings if strings and strings <= _WORDS else set()


def test_no_module_compares_with_a_word_written_as_a_string():
    src = Path(langgap.vocabulary.__file__).parent
    found = []
    for path in sorted(src.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.Compare):
                continue
            operands = [node.left, *node.comparators]
            if set().union(*map(_literal_words, operands)) and not {_field(o) for o in operands} & _OTHER_WORDS:
                found.append(f"{path.relative_to(src)}:{node.lineno}")
    assert not found, f"compare with the word's member in langgap.vocabulary: {found}"


def test_every_flag_offers_plain_strings():
    """argparse's `invalid choice` error quotes each choice's repr: a member's is `<TaskKind.ORIGINAL: ...>`."""
    parsers = [parser for _, parser in cli_parsers(build_parser())]
    actions = [a for p in parsers for a in p._actions if not isinstance(a, argparse._SubParsersAction)]
    choices = [(a.dest, c) for a in actions for c in a.choices or ()]
    defaults = [(a.dest, a.default) for a in actions if isinstance(a.default, str)]
    assert ("kind", "original") in choices and ("stepping", "exact") in defaults
    assert [(dest, value) for dest, value in choices + defaults if type(value) is not str] == []


def test_a_spec_and_its_physics_hold_plain_strings_whatever_words_they_are_given():
    spec = RunSpec.create(
        "noop", tasks="spatial/s0/black-bowl-1-on-plate", episodes=1, conditions=(Condition.GIVEN, Condition.EMPTY),
        stepping=Stepping.FAST, seed_scheme=SeedScheme.OPENPI,
    )  # fmt: skip
    assert repr(spec.conditions) == "('given', 'empty')"
    assert {k: spec.physics[k] for k in stack.CHOSEN} == {"stepping": "fast", "seed_scheme": "openpi"}
    assert all(type(v) is str for v in (*spec.conditions, *spec.physics.values()) if v is not None)
