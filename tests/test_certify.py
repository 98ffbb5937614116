"""Reachability of a drawer's handle, on the real simulator (a few poses of the family)."""

from __future__ import annotations

import pytest

from langgap.catalog.catalog import load_catalog
from langgap.certify import handle_reach
from tests.conftest import run_cli


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap99")


def test_the_middle_drawer_the_oracle_opens_has_a_clear_grasp(catalog):
    found = handle_reach(catalog.get("goal/s0/open-cabinet-middle-drawer"), angles=(0,), along=(0.0,), depths=(0.0,))
    assert len(found.poses) == 2 and found.clear and not found.certified and found.certificate() == ""


def test_the_bottom_drawer_is_blocked_by_the_table_and_the_drawer_above(catalog):
    found = handle_reach(catalog.get("goal/s0/open-cabinet-bottom-drawer"), angles=(0, 35, 90), along=(0.0,),
                         depths=(0.0,))  # fmt: skip
    assert len(found.reachable) == 6 and not found.clear and found.certified
    blockers = {p.angle_deg: p.worst_contact for p in found.reachable}
    assert blockers[0] == "table_collision" and blockers[90].startswith("wooden_cabinet_1_")
    assert round(1000 * found.hook_gap_m) == 16  # narrower than a finger (18 mm)
    assert "16 mm" in found.certificate() and "6 poses" not in found.certificate()


def test_only_drawer_tasks_can_be_certified(tmp_path):
    result = run_cli("certify", "spatial/s0/black-bowl-1-on-plate")
    assert result.returncode == 2
    assert result.stderr.startswith("error: certify analyses tasks whose goal needs one drawer opened")
