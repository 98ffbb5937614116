"""The langgap99 registry: the paper's counts, ids, sources, instructions, selection."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from collections import Counter

import pytest

from langgap.catalog import files
from langgap.catalog.catalog import catalog_from_data, load_catalog
from langgap.errors import CatalogError, UnknownTaskError
from langgap.generation.phrasing import instruction
from langgap.stack import libero_root
from tests.support.harness import REPO, run_cli

ID_FORMAT = re.compile(r"^(spatial|object|goal|libero10)/s\d/[a-z0-9+-]+$")


def test_paper_counts(catalog):
    assert len(catalog) == 99
    originals = [t for t in catalog if t.kind == "original"]
    extended = [t for t in catalog if t.kind == "extended"]
    assert Counter(t.suite for t in originals) == {
        s: 10 for s in ("libero_spatial", "libero_object", "libero_goal", "libero_10")
    }
    assert Counter(t.suite for t in extended) == {"libero_spatial": 28, "libero_goal": 9, "libero_object": 22}
    assert Counter(t.dimension for t in extended) == {
        "change_object": 38,
        "change_target": 13,
        "spatial_description": 5,
        "drawer_action": 3,
    }
    train = [t for t in extended if t.split == "train"]
    assert Counter(t.suite for t in train) == {"libero_spatial": 9, "libero_goal": 3, "libero_object": 4}
    assert sum(t.split == "heldout" for t in extended) == 43
    assert sorted(t.paper_id for t in extended) == list(range(40, 99))
    assert sorted(t.paper_id for t in train) == [40, 41, 42, 43, 44, 45, 49, 50, 51, 54, 59, 62, 63, 64, 78, 79]


def test_ids_are_readable_and_unique(catalog):
    ids = [t.id for t in catalog]
    assert len(set(ids)) == len(ids)
    assert all(ID_FORMAT.match(i) for i in ids), [i for i in ids if not ID_FORMAT.match(i)]
    assert catalog.get("spatial/s0/black-bowl-2-on-plate").paper_id == 40


def test_originals_are_libero_tasks_in_benchmark_order(catalog):
    from libero.libero.benchmark.libero_suite_task_map import libero_task_map

    for task in catalog.select("original"):
        assert libero_task_map[task.suite][task.scene_index] == task.scene_task
        assert task.source == task.id
        assert (libero_root() / "bddl_files" / task.suite / f"{task.scene_task}.bddl").is_file()


def test_extended_tasks_share_their_sources_scene(catalog):
    for task in catalog.select("extended"):
        source = catalog.get(task.source)
        assert source.kind == "original" and source.suite == task.suite
        assert files.init_states_path(task) == files.init_states_path(source)
        assert task.goal != source.goal


def test_tasks_without_released_init_states_say_so(catalog):
    for paper_id in (56, 80, 81):
        (task,) = catalog.select(f"paper:{paper_id}")
        assert task.suite == "libero_goal"
        assert any("no init states" in note for note in task.notes)


def test_libero_style_rederives_every_original(catalog):
    """The phrasing tables reproduce LIBERO's own sentence for all 30 single-goal originals."""
    for task in catalog.select("original"):
        if task.suite != "libero_10":
            assert instruction("libero", task.suite, task.bddl_goal, files.scene_problem(task)) == task.instruction(
                "libero"
            )


def test_extended_libero_sentences_follow_the_originals(catalog):
    for task in catalog.select("extended"):
        assert instruction("libero", task.suite, task.bddl_goal, files.scene_problem(task)) == task.instruction(
            "libero"
        )


def test_change_target_sentences_differ_from_source_only_in_the_target(catalog):
    for task in catalog.select("change_target&libero_spatial"):
        mine = task.instruction().split(" and place it on the ")
        source = catalog.get(task.source).instruction().split(" and place it on the ")
        assert mine[0] == source[0] and mine[1] != source[1]


def test_instruction_styles(catalog):
    task = catalog.get("spatial/s0/black-bowl-1-on-plate")
    assert task.instruction() == "pick up the black bowl between the plate and the ramekin and place it on the plate"
    assert (
        task.instruction("paper")
        == "Pick the akita black bowl between the plate and the ramekin and place it on the plate"
    )
    with pytest.raises(CatalogError):
        task.instruction("shouting")


@pytest.mark.parametrize(
    ("expression", "count"),
    [
        ("all", 99),
        ("original", 40),
        ("extended", 59),
        ("spatial", 38),
        ("libero_goal", 19),
        ("train", 16),
        ("heldout", 43),
        ("change_target", 13),
        ("spatial/s0/*", 13),
        ("paper:0", 1),
        ("spatial&train", 9),
        ("goal/s1/*,object/s0/*", 6),
        ("original&!spatial/s0/*", 39),
        ("spatial&!train&!heldout", 10),
        ("!extended", 40),
    ],
)
def test_selection(catalog, expression, count):
    assert len(catalog.select(expression)) == count


@pytest.mark.parametrize(
    "expression",
    ["spatial/s0/nothing", "nosuch/*", "paper:999", "paper:x", "train&libero_10", "spatial&!spatial", "!nosuch"],
)
def test_selection_errors(catalog, expression):
    with pytest.raises(UnknownTaskError):
        catalog.select(expression)


def test_unknown_id_suggests(catalog):
    with pytest.raises(UnknownTaskError, match="did you mean spatial/s0/black-bowl-2-on-plate"):
        catalog.get("spatial/s0/black-bowl-2-on-plat")


def test_registry_rejects_bad_entries(catalog):
    good = {
        "catalog": "t",
        "max_steps": {"libero_spatial": 220},
        "tasks": [
            {
                "id": "spatial/s0/x",
                "suite": "libero_spatial",
                "kind": "original",
                "libero_task": "a",
                "libero_index": 0,
                "goal": ["(On a b)"],
                "obj_of_interest": ["a"],
                "instructions": {"libero": "x", "paper": "x"},
            }
        ],
    }
    assert len(catalog_from_data(good)) == 1
    bad_goal = json.loads(json.dumps(good))
    bad_goal["tasks"][0]["goal"] = ["(Levitate a)"]
    with pytest.raises(CatalogError, match="unknown predicate"):
        catalog_from_data(bad_goal)

    def with_extended(source: str, dimension: str) -> dict:
        data = json.loads(json.dumps(good))
        extended = {
            "id": "spatial/s0/y",
            "kind": "extended",
            "source": source,
            "dimension": dimension,
            "split": "train",
        }
        data["tasks"].append({**data["tasks"][0], **extended})
        return data

    with pytest.raises(CatalogError, match="dimension"):
        catalog_from_data(with_extended("spatial/s0/x", "change_colour"))
    with pytest.raises(CatalogError, match="not an original"):
        catalog_from_data(with_extended("nope", "change_object"))


def test_cli_list_json_has_every_field():
    result = run_cli("tasks", "list", "--json")
    assert result.returncode == 0, result.stderr
    tasks = json.loads(result.stdout)
    assert len(tasks) == 99
    for field in ("id", "suite", "kind", "dimension", "source", "instruction", "goal", "split", "max_steps"):
        assert all(field in t for t in tasks), field
    assert {t["max_steps"] for t in tasks if t["suite"] == "libero_10"} == {520}
    paper = json.loads(run_cli("tasks", "list", "--json", "--style", "paper", "--suite", "libero_object").stdout)
    assert paper[0]["instruction"] == "Pick the alphabet soup and place it in the basket"


def test_cli_output_cut_short_by_its_reader_ends_quietly():
    # `langgap tasks list | head -1`: the reader leaves after one line; no traceback, the shell's SIGPIPE status.
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    command = [sys.executable, "-m", "langgap.cli.main", "tasks", "list", "--catalog", "libero-plus-language"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    assert process.stdout.readline().startswith(b"id ")
    process.stdout.close()
    assert process.wait(timeout=120) == 141 and process.stderr.read() == b""


def test_cli_list_filters():
    result = run_cli("tasks", "list", "--json", "--dimension", "spatial_description", "--split", "train")
    assert [t["paper_id"] for t in json.loads(result.stdout)] == [40, 41, 42]


def test_cli_show_prints_bddl_and_init_source():
    result = run_cli("tasks", "show", "goal/s5/wine-bottle-on-stove-front")
    assert result.returncode == 0, result.stderr
    assert "wine-bottle-on-stove-front.bddl" in result.stdout
    assert "50 from LIBERO libero_goal task 5" in result.stdout


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("tasks", "show", "spatial/s9/flying-bowl"), "unknown task"),
        (("tasks", "list", "--tasks", "nosuch*"), "matches no task"),
        (("tasks", "list", "--catalog", "nosuch"), "unknown catalog"),
    ],
)
def test_cli_bad_input_is_one_clear_line(args, message):
    result = run_cli(*args)
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: ") and message in result.stderr


def test_custom_registry_with_goal_outside_scene_fails_clearly(tmp_path, catalog):
    task = catalog.get("spatial/s0/black-bowl-2-on-plate")
    data = {
        "catalog": "custom",
        "max_steps": {"libero_spatial": 220},
        "tasks": [
            {
                "id": catalog.get(task.source).id,
                "suite": task.suite,
                "kind": "original",
                "libero_task": task.scene_task,
                "libero_index": 0,
                "goal": ["(On akita_black_bowl_1 plate_1)"],
                "obj_of_interest": ["akita_black_bowl_1"],
                "instructions": {"libero": "a", "paper": "a"},
            },
            {
                "id": "spatial/s0/teapot-on-plate",
                "suite": task.suite,
                "kind": "extended",
                "source": task.source,
                "dimension": "change_object",
                "split": "heldout",
                "goal": ["(On teapot_1 plate_1)"],
                "obj_of_interest": ["teapot_1"],
                "instructions": {"libero": "b", "paper": "b"},
            },
        ],
    }
    path = tmp_path / "custom.yaml"
    path.write_text(json.dumps(data))
    result = run_cli("tasks", "show", "spatial/s0/teapot-on-plate", "--catalog", str(path))
    assert result.returncode == 2
    assert "teapot_1" in result.stderr and "not in the scene" in result.stderr
    assert load_catalog(str(path)).get("spatial/s0/teapot-on-plate").goal_strings == ["(On teapot_1 plate_1)"]
