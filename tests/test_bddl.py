"""BDDL parsing, and generated BDDL that differs from its source in the three task sections only."""

from __future__ import annotations

import pytest

from langgap.bddl import Predicate, parse_bddl, rewrite_task_sections, strip_task_sections
from langgap.catalog import files
from langgap.errors import BddlError
from tests.support.harness import run_cli


def test_every_extended_bddl_differs_from_its_source_only_in_task_sections(catalog):
    for task in catalog.select("extended"):
        source_text = files.scene_bddl_path(task).read_text()
        generated = files.task_bddl_path(task).read_text()
        assert strip_task_sections(generated) == strip_task_sections(source_text), task.id
        problem = parse_bddl(generated)
        assert problem.goal == task.bddl_goal
        assert problem.language == task.instruction("paper")
        assert problem.obj_of_interest == task.obj_of_interest
        assert generated != source_text


def test_originals_use_libero_files_unchanged(catalog):
    for task in catalog.select("original"):
        assert files.task_bddl_path(task) == files.scene_bddl_path(task)


def test_generated_file_is_rewritten_only_when_stale(catalog):
    task = catalog.get("spatial/s0/ramekin-on-plate")
    path = files.task_bddl_path(task)
    path.write_text("stale")
    assert files.task_bddl_path(task).read_text() == files.task_bddl_text(task)


def test_predicate_parsing():
    assert str(Predicate.parse("(on akita_black_bowl_1 plate_1)")) == "(On akita_black_bowl_1 plate_1)"
    assert Predicate.parse("(Turnon flat_stove_1)").as_libero() == ("turnon", "flat_stove_1")
    with pytest.raises(BddlError, match="unknown predicate"):
        Predicate.parse("(Teleport a b)")
    with pytest.raises(BddlError, match="takes 2"):
        Predicate.parse("(On a)")
    with pytest.raises(BddlError):
        Predicate.parse("(On (a) b)")


@pytest.fixture
def source_text(catalog):
    return files.scene_bddl_path(catalog.get("spatial/s0/black-bowl-1-on-plate")).read_text()


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda t: t.replace("(:goal", "(:goal (", 1), "parenthes"),
        (lambda t: t[: t.rindex(")")], "parenthes"),
        (lambda t: t.replace("(:objects", "(:things", 1), "missing section"),
        (lambda t: t.replace("(On akita_black_bowl_1 plate_1)", "(On teapot_1 plate_1)"), "teapot_1"),
        (lambda t: t.replace("(On akita_black_bowl_1 plate_1)", "(Hover akita_black_bowl_1)"), "unknown predicate"),
        (lambda t: t.replace("plate_1 - plate", "plate_1 -"), "typed list"),
    ],
)
def test_malformed_bddl_is_rejected(source_text, mutate, message):
    with pytest.raises(BddlError, match=message):
        parse_bddl(mutate(source_text))


def test_rewrite_rejects_goal_outside_scene(source_text):
    with pytest.raises(BddlError, match="not in the scene"):
        rewrite_task_sections(
            source_text, language="x", obj_of_interest=["a"], goal=[Predicate.parse("(On x plate_1)")]
        )


def test_cli_bddl_check(tmp_path, source_text):
    good = tmp_path / "good.bddl"
    good.write_text(source_text)
    assert run_cli("bddl", str(good)).returncode == 0
    bad = tmp_path / "bad.bddl"
    bad.write_text(source_text.replace("(On akita_black_bowl_1 plate_1)", "(On teapot_1 plate_1)"))
    result = run_cli("bddl", str(bad))
    assert result.returncode == 2
    assert result.stderr.startswith("error: ") and result.stderr.count("\n") == 1 and "teapot_1" in result.stderr
