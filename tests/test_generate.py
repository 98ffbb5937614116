"""The `full` catalog generator: candidates, ids, phrasing, dimensions, the gate seam and the CLI verb."""

from __future__ import annotations

from collections import Counter

import pytest
import yaml

from langgap.bddl import parse_bddl, strip_task_sections
from langgap.catalog import affordances, files
from langgap.catalog.catalog import load_catalog, load_catalog_file
from langgap.catalog.naming import task_id
from langgap.catalog.verdicts import GateResult, record_verdicts
from langgap.cli.main import main
from langgap.generation import phrasing
from langgap.generation.candidates import candidate_goals
from langgap.generation.generate import (
    FULL_CATALOG,
    FULL_DESCRIPTION,
    default_registry_path,
    generate_tasks,
    write_registry,
)
from langgap.generation.registry_writer import registry_data, registry_text

# The generated task space, measured: extended tasks per suite and dimension.
EXPECTED_COUNTS = {
    "libero_spatial": {"change_object": 201, "change_target": 73, "spatial_description": 80, "drawer_action": 40},
    "libero_object": {"change_object": 50},
    "libero_goal": {"change_object": 175, "change_target": 51, "drawer_action": 94},
    "libero_10": {"change_object": 26, "change_target": 15, "drawer_action": 3},
}


@pytest.fixture(scope="module")
def paper():
    return load_catalog("langgap99")


@pytest.fixture(scope="module")
def generated():
    return generate_tasks()


@pytest.fixture(scope="module")
def by_id(generated):
    return {t.id: t for t in generated}


def _init_facts(task):
    return {(f[0].lower(), *f[1:]) for f in files.scene_problem(task).init}


def test_ids_of_the_paper_tasks_are_what_naming_spells(paper):
    for task in paper:
        assert task_id(task.suite, task.scene_index, task.bddl_goal, files.scene_problem(task)) == task.id


def test_phrasing_reproduces_every_single_goal_original_sentence(paper):
    originals = [t for t in paper if t.kind == "original" and t.suite != "libero_10"]
    assert len(originals) == 30
    for task in originals:
        assert (
            phrasing.instruction("libero", task.suite, task.bddl_goal, files.scene_problem(task)) == task.instruction()
        )


def test_paper_template_reproduces_the_authors_strings_except_their_hand_written_bowl_descriptions(paper):
    differ = [
        t.paper_id
        for t in paper
        if t.kind == "extended"
        and phrasing.instruction("paper", t.suite, t.bddl_goal, files.scene_problem(t)) != t.instruction("paper")
    ]
    assert differ == [40, 41, 42, 84]


def test_every_paper_task_is_found_unchanged(paper, by_id):
    for task in paper:
        found = by_id.get(task.id)
        assert found is not None, task.id
        assert found.in_langgap99
        assert (found.suite, found.scene_task, found.scene_index, found.source) == (
            task.suite,
            task.scene_task,
            task.scene_index,
            task.source,
        )
        assert found.goal == task.goal
        assert found.obj_of_interest == task.obj_of_interest
        assert found.instructions == task.instructions
        assert (found.kind, found.dimension, found.split, found.paper_id) == (
            task.kind,
            task.dimension,
            task.split,
            task.paper_id,
        )
    assert sum(t.in_langgap99 for t in by_id.values()) == len(paper) == 99


def test_single_goal_originals_are_among_their_scene_candidates(paper):
    for task in paper:
        if task.kind == "original" and len(task.bddl_goal) == 1:
            assert task.bddl_goal[0] in candidate_goals(files.scene_problem(task), task.bddl_goal), task.id


def test_the_paper_label_is_kept_where_the_dimension_rule_differs(by_id):
    differing = [t.id for t in by_id.values() if any("dimension rule" in n for n in t.notes)]
    assert differing == ["goal/s5/wine-bottle-on-stove-front"]
    assert by_id["goal/s5/wine-bottle-on-stove-front"].dimension == "change_target"


def test_generation_is_deterministic_and_the_shipped_registry_is_current(generated):
    text = registry_text(FULL_CATALOG, "d", generated)
    assert registry_text(FULL_CATALOG, "d", generate_tasks()) == text
    shipped = default_registry_path().read_text(encoding="utf-8")
    assert shipped == registry_text(FULL_CATALOG, FULL_DESCRIPTION, generated), "run `langgap generate`"


def test_registry_text_loads_back_to_its_data(generated):
    text = registry_text(FULL_CATALOG, "a description: with 'quotes'", generated)
    assert yaml.safe_load(text) == registry_data(FULL_CATALOG, "a description: with 'quotes'", generated)


def test_full_catalog_loads_with_unique_ids_and_shared_scenes(generated):
    catalog = load_catalog("full")
    assert [t.id for t in catalog] == [t.id for t in generated]
    assert len({t.id for t in catalog}) == len(catalog)
    assert all(t.gate is not None for t in catalog)  # every candidate went through the gate
    feasible = [t.id for t in catalog if t.feasible]
    assert 0 < len(feasible) < len(catalog) and [t.id for t in catalog.select(None)] == feasible
    assert len(catalog.select("langgap99")) == 99
    assert len(load_catalog("langgap99").select("langgap99")) == 99


def test_counts_per_suite_and_dimension(generated):
    counts = Counter((t.suite, t.dimension) for t in generated if t.kind == "extended")
    measured = {suite: {d: counts[(suite, d)] for d in dims} for suite, dims in EXPECTED_COUNTS.items()}
    print("\nextended tasks per suite and dimension:", measured)
    assert measured == EXPECTED_COUNTS
    assert sum(counts.values()) == sum(sum(d.values()) for d in EXPECTED_COUNTS.values()) == len(generated) - 40


def test_no_goal_is_true_at_t0_by_construction(generated):
    for task in (t for t in generated if t.kind == "extended"):
        (goal,) = task.bddl_goal
        facts = _init_facts(task)
        if goal.name in ("On", "In"):
            obj, target = goal.args
            assert obj != target
            assert ("on", obj, target) not in facts and ("in", obj, target) not in facts, task.id
        elif goal.name in ("Open", "Turnon"):
            assert (goal.name.lower(), *goal.args) not in facts, task.id
        else:  # Close / Turnoff: only what is open / on at t0
            opposite = {"Close": "open", "Turnoff": "turnon"}[goal.name]
            assert (opposite, *goal.args) in facts, task.id


def test_receive_rules_leave_out_meaningless_pairs(generated):
    placements = [
        (t, *t.bddl_goal[0].args) for t in generated if t.kind == "extended" and t.bddl_goal[0].name in ("On", "In")
    ]
    for task, obj, target in placements:
        scene = files.scene_problem(task)
        obj_category = scene.objects[obj]
        target_category = scene.objects.get(target)
        assert obj_category != "basket"
        assert target_category not in ("wine_bottle", "ketchup", "milk", "salad_dressing", "bbq_sauce")
        if obj_category == "plate":
            assert target_category is None, f"{task.id}: a plate onto an object"
        if target == "wine_rack_1_top_region":
            assert obj_category == "wine_bottle"
        if "contain_region" in target and target.startswith("basket"):
            assert obj_category in affordances.RECEIVES["basket.contain_region"].takes
    pairs = {(files.scene_problem(t).objects[o], files.scene_problem(t).objects.get(g)) for t, o, g in placements}
    assert ("plate", "akita_black_bowl") not in pairs
    assert ("glazed_rim_porcelain_ramekin", "cookies") in pairs  # the paper's task 72


def test_conjuncts_of_a_libero_10_source_are_not_candidates(generated, paper):
    sources = {t.id: t for t in paper if t.suite == "libero_10" and t.kind == "original"}
    for task in (t for t in generated if t.suite == "libero_10" and t.kind == "extended"):
        assert task.bddl_goal[0] not in sources[task.source].bddl_goal, task.id


def test_every_generated_bddl_parses_with_its_goal_and_the_source_scene(generated):
    for task in generated:
        text = files.task_bddl_text(task)
        parsed = parse_bddl(text, source=task.id)
        assert parsed.goal == task.bddl_goal
        if task.kind == "extended":
            assert parsed.language == task.instruction("paper")
            scene_text = files.task_bddl_text(load_catalog("full").get(task.source))
            assert strip_task_sections(text) == strip_task_sections(scene_text)


def test_dimension_rules_relative_to_the_source(by_id):
    expect = {
        "spatial/s0/black-bowl-2-on-stove": "spatial_description",  # same category, other instance
        "spatial/s0/turn-on-stove": "drawer_action",  # articulation vs pick-and-place
        "goal/s0/open-cabinet-top-drawer": "change_object",  # same action, another drawer (paper's 57)
        "goal/s7/black-bowl-on-plate": "drawer_action",  # pick-and-place vs turning the stove on
        "libero10/s4/white-mug-on-plate-2": "change_target",  # same mug as a source conjunct
        "libero10/s4/red-mug-on-plate-1": "change_object",
        "libero10/s8/turn-off-stove": "drawer_action",
    }
    assert {i: by_id[i].dimension for i in expect} == expect


def test_libero_10_sentences_follow_libero_90(by_id):
    assert by_id["libero10/s2/frying-pan-on-stove"].instruction() == "put the frying pan on the stove"
    assert by_id["libero10/s8/turn-off-stove"].instruction() == "turn off the stove"
    assert by_id["libero10/s4/red-mug-on-plate-2"].instruction() == "put the red mug on the right plate"
    assert by_id["libero10/s7/ketchup-in-basket"].instruction() == "pick up the ketchup and put it in the basket"
    assert by_id["libero10/s5/yellow-white-mug-on-caddy-right"].instruction("paper") == (
        "pick up the yellow and white mug and place it to the right of the caddy"
    )


def test_recorded_verdicts_flag_rejected_tasks_and_survive_regeneration(tmp_path):
    """Verdicts live beside the registry: rejected tasks stay listed, leave the default selection, and
    regenerating the registry keeps them."""
    path = write_registry(generate_tasks(["object"]), tmp_path / "gated.yaml")
    catalog = load_catalog_file(path)
    milk = {t.id for t in catalog if t.bddl_goal[0].args[0] == "milk_1"}
    verdicts = {
        t.id: GateResult(
            episodes=4,
            successes=0 if t.id in milk else 3,
            feasible=t.id not in milk,
            reason="oracle 0/4" if t.id in milk else "",
        )
        for t in catalog
    }
    record_verdicts(path, verdicts, {"policy": "test"})
    write_registry(generate_tasks(["object"]), path)
    catalog = load_catalog_file(path)
    assert {t.id for t in catalog if not t.feasible} == milk and len(milk) == 6
    assert catalog.get("object/s0/milk-in-basket").gate == GateResult(4, 0, False, "oracle 0/4")
    assert catalog.get("object/s0/butter-in-basket").gate.rate == 0.75
    assert {t.id for t in catalog.select(None)} == {t.id for t in catalog} - milk
    assert {t.id for t in catalog.select("rejected")} == milk


def test_cli_generate_writes_a_loadable_registry_and_prints_counts(tmp_path, capsys):
    out = tmp_path / "sub" / "full.yaml"
    assert main(["generate", "--out", str(out), "--suites", "goal", "libero_object"]) == 0
    printed = capsys.readouterr().out
    assert "goal/s7/turn-on-stove" in printed and "object/s0/alphabet-soup-in-basket" in printed
    assert "390 tasks: 20 original, 370 extended" in printed
    assert "langgap99: 51/51 of the paper's tasks in these suites found" in printed
    catalog = load_catalog_file(out)
    assert {t.suite for t in catalog} == {"libero_goal", "libero_object"} and len(catalog) == 390


def test_cli_generate_rejects_an_unknown_suite(tmp_path, capsys):
    assert main(["generate", "--out", str(tmp_path / "x.yaml"), "--suites", "libero_90"]) == 2
    assert "unknown suite 'libero_90'" in capsys.readouterr().err
    assert not (tmp_path / "x.yaml").exists()


# One generated (non-paper) task per suite, built in the real simulator from its generated BDDL.
_SIM_SAMPLES = [
    "spatial/s4/close-cabinet-top-drawer",
    "goal/s2/wine-bottle-in-cabinet-bottom-drawer",
    "object/s7/chocolate-pudding-in-basket",
    "libero10/s8/turn-off-stove",
]


@pytest.mark.parametrize("task_id_", _SIM_SAMPLES)
def test_generated_task_builds_in_the_simulator_with_its_goal_false_at_t0(task_id_, tmp_path, monkeypatch):
    from langgap.sim.env import TaskEnv

    monkeypatch.setenv("LANGGAP_CACHE", str(tmp_path))
    task = load_catalog("full").get(task_id_)
    assert not task.in_langgap99
    with TaskEnv(task) as env:
        env.reset(0)
        env.settle()
        assert env.robosuite_env.parsed_problem["goal_state"] == [list(p.as_libero()) for p in task.bddl_goal]
        assert not env.success()


@pytest.mark.slow
def test_no_candidate_goal_holds_at_t0_in_simulation():
    """Every extended task's goal is false at init state 0 after settling (one env per source scene)."""
    from langgap.sim.env import TaskEnv

    catalog = load_catalog("full")
    holding = []
    for source in (t for t in catalog if t.kind == "original"):
        extended = [t for t in catalog if t.source == source.id and t.kind == "extended"]
        with TaskEnv(source) as env:
            env.reset(0)
            env.settle()
            holding += [t.id for t in extended if all(env.predicate_holds(p) for p in t.bddl_goal)]
    assert holding == []


@pytest.mark.slow
def test_generate_gates_every_candidate_and_records_how(tmp_path):
    out = tmp_path / "object.yaml"
    args = ["generate", "--suites", "libero_object", "--out", str(out), "--gate-inits", "1", "--stepping", "fast"]
    assert main([*args, "--workers", "2", "--no-progress"]) == 0
    catalog = load_catalog_file(out)
    assert len(catalog.tasks) == 60 and all(t.gate is not None and t.gate.inits == 1 for t in catalog.tasks)
    assert all(t.gate.made_by.endswith(", fast stepping") for t in catalog.tasks)  # the flag reached the record
