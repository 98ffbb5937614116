"""The figures the docs take from the registries and stored audits are what the code counts now
(`tools/docs_counts.py`): a re-gate or a new audit that moves one fails here until the pages say it."""

from __future__ import annotations

import pytest

from tests.support.harness import REPO, run_cli
from tools.docs_counts import PAGES, REGION, CountsError, generate, rewrite, stale_regions


def test_every_generated_region_of_the_docs_is_current():
    stale = stale_regions()
    assert stale == [], f"run `python -m tools.docs_counts` to rewrite: {stale}"


def test_the_pages_hold_the_catalogs_verdicts_and_audits():
    named = {m["what"] for page in PAGES for m in REGION.finditer((REPO / page).read_text())}
    catalogs = ("langgap99", "full", "langgap-beyond", "libero-pro", "libero-plus-language")
    assert {f"verdicts {c}" for c in catalogs} <= named
    assert {"langgap tasks audit --catalog libero-pro --examples 2"} <= named


def test_a_figure_edited_by_hand_is_rewritten_to_what_tasks_gate_counts():
    edited = "it has <!-- generated: verdicts full -->848 tasks: 700 doable<!-- /generated --> in all"
    phrase = generate("verdicts full")
    assert rewrite(edited) == f"it has <!-- generated: verdicts full -->{phrase}<!-- /generated --> in all" != edited
    lines = run_cli("tasks", "gate", "--catalog", "full").stdout.splitlines()
    (total,) = [line.split() for line in lines if line.startswith("total") and line.split()[1] == "all"]
    row = dict(zip(lines[0].split(), total, strict=True))
    assert phrase == f"{int(row['tasks']):,} tasks: {row['doable']} doable, {row['unproven']} unproven"


def test_only_read_only_commands_may_fill_a_region():
    for what in ("langgap eval --policy noop --run r", "langgap tasks audit --catalog libero-pro --record", "sum 1 2"):
        with pytest.raises(CountsError):
            generate(what)
