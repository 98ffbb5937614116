"""The search for a demonstration where the oracle fails, and replaying what it stores (real LIBERO simulation)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

import langgap
from langgap.catalog.catalog import load_catalog, registry_path
from langgap.demos.searched import Demonstration, DemonstrationError, replay_env, verify
from langgap.engine.plan import episode_seed
from langgap.engine.spec import ExecutionOptions
from langgap.search import demonstrate, search

DRAWER = "goal/s0/open-cabinet-bottom-drawer"
WITHOUT_THE_PRESSED_DRAG = {"drawer": "grasp"}  # the oracle before it opened bottom drawers: 0/50


@pytest.fixture(scope="module")
def found(catalog):
    """The search's demonstration of the bottom drawer on init state 0, with the oracle's own pressed drag off."""
    task = catalog.get(DRAWER)
    result = search(task, catalog, init_index=0, seed=episode_seed(0, 0), stepping="exact", budget=16,
                    oracle_args=WITHOUT_THE_PRESSED_DRAG)  # fmt: skip
    assert result.found is not None, [(str(c), ok, steps) for c, ok, steps in result.tried]
    return result


def test_the_search_finds_the_bottom_drawer_without_the_oracles_pressed_drag(found):
    # Every candidate draws its drawer primitive; those that grasp the handle fail, as the oracle did;
    # the one that succeeds drew a pressed drag (its tilt, turn and depth searched, not the oracle's).
    demo = found.found
    assert "drawer=press:" in demo.found_by and demo.steps < 300
    assert all(not ok for candidate, ok, _ in found.tried if candidate.policy_args["drawer"] == "grasp")


def test_a_stored_demonstration_replays_to_its_goal_at_its_step(found, catalog, tmp_path):
    stored = Demonstration.load(found.found.save(tmp_path / "init-00.npz"))
    assert stored.steps == found.found.steps and (stored.actions == found.found.actions).all()
    with replay_env(catalog.get(DRAWER), "exact") as env:
        verify(env, stored, catalog)  # raises unless the goal first holds at the recorded step
        cut = replace(stored, steps=stored.steps - 15, actions=stored.actions[:-15])
        with pytest.raises(DemonstrationError, match="actions end before the goal holds"):
            verify(env, cut, catalog)


def test_the_gate_keeps_only_what_replays_from_the_file(catalog, tmp_path):
    here = ExecutionOptions(workers=0, progress=False)
    shown = demonstrate("langgap99", {DRAWER: [(0, episode_seed(0, 0))]}, tmp_path, stepping="exact", budget=16,
                        oracle_args=WITHOUT_THE_PRESSED_DRAG, options=here)  # fmt: skip
    assert shown == {DRAWER: [0]} and (tmp_path / DRAWER / "init-00.npz").is_file()


SHIPPED = sorted((Path(langgap.__file__).parent / "catalog" / "registry" / "demonstrations").rglob("init-*.npz"))


@pytest.mark.parametrize("path", SHIPPED, ids=[p.parent.name + "/" + p.stem for p in SHIPPED])
def test_every_shipped_demonstration_replays_to_its_goal(path):
    # A verdict accepted on a searched demonstration rests on this file alone.
    demo = Demonstration.load(path)
    catalog = load_catalog(demo.catalog)
    gate = catalog.get(demo.task_id).gate
    assert gate is not None and demo.init_index in gate.demonstrated_inits
    assert path.parent == registry_path(demo.catalog).parent / gate.demonstration
    with replay_env(catalog.get(demo.task_id), demo.stepping) as env:
        verify(env, demo, catalog)
