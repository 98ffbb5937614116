"""The plan of a run and the validation of what a run is and how it runs."""

from __future__ import annotations

import dataclasses

import pytest

from langgap.catalog.catalog import load_catalog
from langgap.engine.plan import build_plan, condition_instruction, episode_seed, repeat_of
from langgap.engine.spec import ExecutionOptions, RunSpec, SpecError
from langgap.errors import LangGapError


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap99")


def test_every_task_condition_and_init_index_once_with_shared_seeds(catalog):
    tasks = catalog.select("spatial/s0/black-bowl-1-on-plate,spatial/s0/ramekin-on-plate,goal/s7/turn-on-stove")
    plan = build_plan(tasks, catalog, episodes=3, seed=10, conditions=("given", "empty"), first_init=2)
    assert len(plan) == 3 * 2 * 3 and len({p.key for p in plan}) == len(plan)
    assert {(p.key.init_index, p.key.seed) for p in plan} == {(k, episode_seed(10, k)) for k in (2, 3, 4)}
    assert episode_seed(10, 3) == 13  # the init index, not the task: siblings start from the identical scene
    scenes = {p.key.task_id: p.scene for p in plan}
    assert scenes["spatial/s0/black-bowl-1-on-plate"] == scenes["spatial/s0/ramekin-on-plate"]
    assert scenes["goal/s7/turn-on-stove"] != scenes["spatial/s0/ramekin-on-plate"]
    empty = [p for p in plan if p.key.condition == "empty"]
    assert empty and all(p.instruction == "" for p in empty)
    given = next(p for p in plan if p.key == p.key.__class__("goal/s7/turn-on-stove", 2, 12, "given"))
    assert given.instruction == catalog.get("goal/s7/turn-on-stove").instruction("libero")


def test_conditions_are_deterministic_and_come_from_the_scene(catalog):
    task = catalog.get("spatial/s0/black-bowl-2-on-plate")
    assert condition_instruction(task, catalog, "source", "paper", 0) == catalog.get(task.source).instruction("paper")
    shuffled = [condition_instruction(task, catalog, "shuffled", "libero", k) for k in range(10)]
    assert shuffled == [condition_instruction(task, catalog, "shuffled", "libero", k) for k in range(10)]
    assert task.instruction() not in shuffled
    assert set(shuffled) <= {t.instruction() for t in catalog.scene_mates(task)}


def test_init_indices_past_the_fifty_states_are_an_error(catalog):
    with pytest.raises(LangGapError, match="has 50 init states; init indices 45..50 are out of range"):
        build_plan(catalog.select("spatial/s0/black-bowl-1-on-plate"), catalog, episodes=6, first_init=45)
    with pytest.raises(LangGapError, match="unknown condition"):
        build_plan(catalog.select("spatial/s0/black-bowl-1-on-plate"), catalog, episodes=1, conditions=("loud",))


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"workers": -1}, "--workers must be at least 0"),
        ({"backend": "ray", "workers": 0}, "--workers must be at least 1"),
        ({"workers": 0, "timeout_s": 10}, "--timeout needs worker processes"),
        ({"timeout_s": 0}, "--timeout must be positive"),
        ({"max_batch": 4}, "--shared-policy"),
        ({"backend": "ray", "shared_policy": True, "max_batch": 0}, "--max-batch"),
        ({"max_attempts": 0}, "--max-attempts"),
        ({"max_failure_streak": 0}, "--max-failure-streak"),
    ],
)
def test_execution_options_are_validated(options, message):
    with pytest.raises(SpecError, match=message):
        ExecutionOptions(**options)


def test_execution_defaults():
    assert ExecutionOptions().episode_timeout_s == 900 and ExecutionOptions(workers=0).episode_timeout_s is None
    assert ExecutionOptions(timeout_s=30).episode_timeout_s == 30


def test_a_spec_names_every_field_that_differs():
    spec = RunSpec(
        policy="noop", policy_args={}, catalog="langgap99", catalog_hash="abc", selection=None, tasks=("a", "b"),
        inits=(0, 1), seed=0, repeats=1, conditions=("given",), style="libero", physics={"mujoco": "3.2.3"},
    )  # fmt: skip
    stored = spec.to_dict()
    assert spec.differences(stored) == []
    other = dataclasses.replace(spec, seed=5, inits=(0, 1, 2))
    assert other.differences(stored) == ["inits", "seed"]
    assert other.describe_differences(stored, ["seed"]) == "seed: stored 0, given 5"
    assert stored["tasks"] == ["a", "b"]  # stored as JSON lists


def test_repeats_run_each_init_state_with_other_seeds(catalog):
    tasks = catalog.select("spatial/s0/black-bowl-1-on-plate")
    plan = build_plan(tasks, catalog, episodes=2, seed=3, repeats=3)
    assert sorted((p.key.init_index, p.key.seed) for p in plan) == [
        (0, 3), (0, 1003), (0, 2003), (1, 4), (1, 1004), (1, 2004)
    ]  # fmt: skip
    assert {repeat_of(p.key.seed, p.key.init_index, 3) for p in plan} == {0, 1, 2}
