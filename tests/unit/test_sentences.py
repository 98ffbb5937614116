"""The audit's sentence check: a goal must accept what its sentence allows (LIBERO's BDDL files, no simulator)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from langgap.catalog import files
from langgap.catalog.catalog import load_catalog
from langgap.goals import And, Atom, Not, Or
from langgap.validity.sentences import TEMPLATES, sentence_findings, template_counts

NOT_WHERE = "spatial/s0/black-bowl-1-on-plate~not-where"
NOT_WHAT = "spatial/s5/black-bowl-1-on-plate~not-what"


@pytest.fixture(scope="module")
def beyond():
    return load_catalog("langgap-beyond")


def _findings(task) -> list[tuple[str, str]]:
    return [(f.name, f.detail) for f in sentence_findings(task, files.scene_problem(task))]


def _without(task, dropped: set[str]):
    """`task` with the `Or` of its negation goal lacking the alternatives named in `dropped` (as strings)."""
    alternatives, negated = task.goal.parts
    kept = tuple(a for a in alternatives.parts if str(a) not in dropped)
    return replace(task, goal=And((Or(kept), negated)))


@pytest.mark.parametrize("catalog", ["langgap99", "full", "langgap-beyond"])
def test_langgaps_own_catalogs_have_no_goal_narrower_or_wider_than_its_sentence(catalog):
    tasks = list(load_catalog(catalog))
    assert [f for t in tasks for f in sentence_findings(t, files.scene_problem(t))] == []
    counts = template_counts(tasks, files.scene_problem)
    assert sum(counts.values()) == len(tasks) and set(counts) <= set(TEMPLATES)


def test_anywhere_but_without_moved_is_narrower_than_its_sentence(beyond):
    task = beyond.get(NOT_WHERE)
    assert "(Moved akita_black_bowl_1)" in {str(a) for a in task.goal.parts[0].parts}
    assert _findings(task) == []
    # the goal the catalog shipped before: eight named places, the bare table not among them
    ((name, detail),) = _findings(_without(task, {"(Moved akita_black_bowl_1)"}))
    assert name == "goal narrower than its sentence" and "8 named places" in detail


def test_anything_but_must_list_every_other_object_the_receiver_takes(beyond):
    task = beyond.get(NOT_WHAT)
    assert _findings(task) == []
    # the cookie box holds the other bowl at t0: the sentence still allows clearing it and putting it on the plate
    ((name, detail),) = _findings(_without(task, {"(On cookies_1 plate_1)"}))
    assert name == "goal narrower than its sentence" and detail == "not accepted: (On cookies_1 plate_1)"


def test_a_negation_that_does_not_exclude_the_negated_goal_is_wider_than_its_sentence(beyond):
    task = beyond.get(NOT_WHERE)
    alternatives, _ = task.goal.parts
    assert isinstance(alternatives, Or) and isinstance(task.goal.parts[1], Not)
    wider = replace(task, goal=And((alternatives, Atom(alternatives.parts[0].predicate))))
    assert [name for name, _ in _findings(wider)] == ["goal wider than its sentence"]


def test_every_task_falls_under_the_template_its_sentence_follows(beyond):
    counts = template_counts(beyond, files.scene_problem)
    assert counts["not-where"] == 17 and counts["not-what"] == 26 and counts["ordering"] == 176
    assert counts["push"] == 5  # "push the plate to the front of the stove" and its paraphrases
