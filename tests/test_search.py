"""The search for a demonstration where the oracle fails, and replaying what it stores (real LIBERO simulation)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import langgap
import langgap.gate.search
from langgap.catalog.catalog import load_catalog
from langgap.engine.plan import episode_seed
from langgap.engine.spec import ExecutionOptions
from langgap.errors import LangGapError
from langgap.gate.demonstrations import Demonstration, DemonstrationError, replay_env, verdict_evidence, verify
from langgap.gate.search import demonstrate, search
from tests.support.harness import run_cli

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


def test_a_find_that_does_not_replay_from_its_file_shows_nothing(found, tmp_path, monkeypatch):
    """The gate counts a searched init state only after the stored file replays to the goal at its recorded step:
    a find whose actions were cut (the search's result altered, nothing else) stops the search with the replay's
    error, and the task gains no init state."""
    cut = replace(found.found, steps=found.found.steps - 15, actions=found.found.actions[:-15])
    monkeypatch.setattr(langgap.gate.search, "search", lambda *args, **kwargs: replace(found, found=cut))
    here = ExecutionOptions(workers=0, progress=False, max_attempts=1)
    with pytest.raises(LangGapError, match=r"init 0: the replay fails: its \d+ actions end before the goal holds"):
        demonstrate("langgap99", {DRAWER: [(0, episode_seed(0, 0))]}, tmp_path, stepping="exact", options=here)


def _shipped() -> list:
    """Every shipped demonstration; only each task's first runs outside `slow` (all 108 take ~8 min on 2 cores)."""
    paths = sorted((Path(langgap.__file__).parent / "catalog" / "registry" / "demonstrations").rglob("init-*.npz"))
    first = {path.parent: path for path in reversed(paths)}.values()
    return [
        pytest.param(path, id=path.parent.name + "/" + path.stem, marks=() if path in first else pytest.mark.slow)
        for path in paths
    ]


@pytest.mark.parametrize("path", _shipped())
def test_every_shipped_demonstration_replays_to_its_goal(path):
    # A verdict accepted on a searched demonstration rests on this file alone.
    demo = Demonstration.load(path)
    catalog = load_catalog(demo.catalog)
    gate = catalog.get(demo.task_id).gate
    assert gate is not None and demo.init_index in gate.demonstrated_inits
    assert verdict_evidence(catalog.get(demo.task_id), demo.catalog)[2][demo.init_index] == path
    with replay_env(catalog.get(demo.task_id), demo.stepping) as env:
        verify(env, demo, catalog)


REPLAYED = "spatial/s5/black-bowl-1-on-plate"  # the oracle fails init state 1; a searched demonstration does it


def _registry_copy(tmp_path: Path) -> tuple[str, Path, Demonstration]:
    """LangGap-99's registry copied to `tmp_path` without its demonstrations: the copy's path, where the copy looks
    for REPLAYED's init-1 file, and the shipped file's demonstration."""
    registry = Path(langgap.__file__).parent / "catalog" / "registry"
    for name in ("langgap99.yaml", "langgap99.gate.json"):
        (tmp_path / name).write_bytes((registry / name).read_bytes())
    copy = str(tmp_path / "langgap99.yaml")
    file = verdict_evidence(load_catalog(copy).get(REPLAYED), copy)[2][1]
    file.parent.mkdir(parents=True)
    return copy, file, Demonstration.load(registry / file.relative_to(tmp_path))


def test_tasks_replay_replays_a_verdicts_demonstrations_and_fails_a_damaged_one(tmp_path):
    shown = run_cli("tasks", "replay", "--catalog", "langgap99", "--tasks", REPLAYED)
    assert shown.returncode == 0, shown.stderr
    steps = Demonstration.load(verdict_evidence(load_catalog("langgap99").get(REPLAYED), "langgap99")[2][1]).steps
    assert shown.stdout.splitlines() == [
        f"{REPLAYED} init 1: reaches its goal at step {steps}, as recorded",
        "1/1 stored demonstration(s) of 1 task(s) replay to their goals",
    ]
    # A copy of the registry whose file lost its last action: the replay, not the file's claim, decides.
    copy, file, demo = _registry_copy(tmp_path)
    replace(demo, steps=demo.steps - 1, actions=demo.actions[:-1]).save(file)
    damaged = run_cli("tasks", "replay", "--catalog", copy, "--tasks", REPLAYED)
    assert damaged.returncode == 1
    assert damaged.stdout.splitlines()[0].startswith(f"{REPLAYED} init 1: FAIL: the replay fails")
    assert damaged.stdout.splitlines()[-1] == "0/1 stored demonstration(s) of 1 task(s) replay to their goals"
    nothing = run_cli("tasks", "replay", "--catalog", "langgap99", "--tasks", "spatial/s0/*")
    assert nothing.returncode == 0 and "no verdict of the" in nothing.stdout


def test_tasks_replay_remake_keeps_what_does_the_task_here_and_leaves_the_rest(tmp_path):
    # Files another stack recorded, as they replay here: actions that reach the goal sooner are kept up to there;
    # actions that run out before it are replaced by the episode their finder (found_by) plays again, closed loop.
    copy, file, demo = _registry_copy(tmp_path)
    command = ("tasks", "replay", "--catalog", copy, "--tasks", REPLAYED, "--remake")
    cases = [
        (replace(demo, steps=demo.steps + 5, actions=np.vstack([demo.actions, np.zeros((5, 7))])), "recorded actions"),
        (replace(demo, steps=demo.steps - 1, actions=demo.actions[:-1]), "finder"),
    ]
    for damaged, how in cases:
        damaged.save(file)
        remade = run_cli(*command)
        assert remade.returncode == 0, remade.stderr
        assert remade.stdout.splitlines() == [
            f"{REPLAYED} init 1: remade from its {how}: reaches its goal at step {demo.steps} (was {damaged.steps})",
            "1/1 stored demonstration(s) of 1 task(s) replay to their goals",
        ]
        again = Demonstration.load(file)
        assert again.found_by == demo.found_by and again.made_with["physics"]["blas"]
        assert sorted(p.name for p in file.parent.iterdir()) == [file.name]  # nothing left beside it
        assert run_cli("tasks", "replay", "--catalog", copy, "--tasks", REPLAYED).returncode == 0
    # neither: the file stays as it was (the plain oracle fails this init state) and the line says to search again
    lost = replace(demo, steps=demo.steps - 1, actions=demo.actions[:-1], found_by="oracle")
    lost.save(file)
    kept = file.read_bytes()
    failed = run_cli(*command)
    assert failed.returncode == 1 and file.read_bytes() == kept
    assert failed.stdout.splitlines()[0].endswith(
        "neither its actions nor its finder (oracle) do the task here: search again"
    )
