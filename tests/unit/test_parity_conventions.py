"""The conventions of openpi's LIBERO example that LangGap shares, as constants (docs/parity.md); the
simulated ones are compared bit for bit in tests/test_parity.py."""

from __future__ import annotations

import re

import numpy as np

from langgap import stack
from langgap.catalog.catalog import load_catalog
from langgap.sim.env import SETTLE_ACTION, SETTLE_STEPS
from langgap.vocabulary import Stepping
from tests.support.harness import REPO

# openpi's examples/libero/main.py: max_steps per suite, num_steps_wait, LIBERO_DUMMY_ACTION.
OPENPI_MAX_STEPS = {"libero_spatial": 220, "libero_object": 280, "libero_goal": 300, "libero_10": 520}
OPENPI_SETTLE_STEPS = 10
OPENPI_DUMMY_ACTION = [0.0] * 6 + [-1.0]


def test_step_limits_are_openpis_per_suite():
    originals = [task for task in load_catalog("langgap99") if task.kind == "original"]
    assert {task.suite for task in originals} == set(OPENPI_MAX_STEPS)
    for task in originals:
        assert task.max_steps == OPENPI_MAX_STEPS[task.suite], task.id


def test_settle_is_openpis_wait():
    assert SETTLE_STEPS == OPENPI_SETTLE_STEPS
    assert SETTLE_ACTION.dtype == np.float64 and SETTLE_ACTION.tolist() == OPENPI_DUMMY_ACTION


def test_every_result_records_the_start_and_image_conventions():
    for stepping in Stepping:
        physics = stack.physics_stack(stepping)
        assert physics["start"] == "fresh-env" and physics["images"] == "robosuite-sample"


def test_every_row_of_the_parity_page_names_tests_that_exist():
    """docs/parity.md's conventions table: each row's last cell names at least one test, and each exists."""
    page = (REPO / "docs" / "parity.md").read_text()
    table = page.split("## Conventions side by side", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in table.splitlines() if line.startswith("| ") and not line.startswith("| Convention")]
    assert len(rows) >= 12
    for row in rows:
        named = re.findall(r"`((?:unit/)?test_\w+\.py)::(\w+)`", row.rstrip(" |").rsplit("|", 1)[1])
        assert named, f"no test behind: {row[:60]}"
        for file, name in named:
            assert f"def {name}(" in (REPO / "tests" / file).read_text(), f"{file}::{name} does not exist"
