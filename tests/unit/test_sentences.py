"""The audit's sentence check: a goal must accept what its sentence allows (LIBERO's BDDL files, no simulator)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from langgap.audit.findings import Finding
from langgap.audit.sentences import TEMPLATES, sentence_findings, template_counts, template_of, templates_text
from langgap.catalog import files
from langgap.catalog.catalog import load_catalog
from langgap.goals import And, Atom, Not, Or

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


def _all(task) -> list[Finding]:
    return sentence_findings(task, files.scene_problem(task))


def test_a_negation_without_alternatives_is_narrower_and_one_without_its_negation_is_wider(beyond):
    task = beyond.get(NOT_WHERE)
    alternatives, negated = task.goal.parts
    assert _all(replace(task, goal=negated)) == [
        Finding("goal narrower than its sentence", NOT_WHERE, "no alternative to the negated goal")
    ]
    # only one place, and no negation: both findings, each naming the task
    one = replace(task, goal=And((Or(alternatives.parts[:1]),)))
    assert _all(one) == [
        Finding("goal wider than its sentence", NOT_WHERE, "nothing excludes what the sentence negates"),
        Finding(
            "goal narrower than its sentence",
            NOT_WHERE,
            "akita_black_bowl_1 set down elsewhere (the bare table) fails: the goal accepts 1 named places only",
        ),
    ]


def test_anything_but_names_every_object_it_leaves_out_and_reads_the_receiver_without_a_negation(beyond):
    task = beyond.get(NOT_WHAT)
    dropped = {"(On cookies_1 plate_1)", "(On akita_black_bowl_2 plate_1)"}
    assert _all(_without(task, dropped)) == [
        Finding("goal narrower than its sentence", NOT_WHAT, "not accepted: " + ", ".join(sorted(dropped)))
    ]
    alternatives, _ = task.goal.parts
    first = alternatives.parts[0]
    findings = _all(replace(task, goal=And((Or((first,)),))))
    assert [f.name for f in findings] == ["goal wider than its sentence", "goal narrower than its sentence"]
    assert str(first) not in findings[1].detail and "(On akita_black_bowl_1 plate_1)" in findings[1].detail


def test_the_negation_template_is_the_last_variant_of_a_negation_tasks_id(beyond):
    task = beyond.get(NOT_WHERE)
    scene = files.scene_problem(task)
    assert template_of(replace(task, id="spatial/s0/bowl~paraphrase~not-where"), scene) == "not-where"
    assert template_of(replace(task, id="spatial/s0/bowl~other"), scene) == "both"  # read from the goal's form
    assert template_of(replace(task, dimension="paraphrase"), scene) == "both"


def test_the_templates_text_says_what_each_used_template_allows_and_checks():
    place = TEMPLATES["place"]
    assert templates_text({"place": 2, "push": 1}).splitlines()[:5] == [
        f"place: 2 task(s), e.g. {place.example!r}",
        f"  sentence allows: {place.allows}",
        f"  goal checks: {place.checks}",
        f"  verdict: {place.verdict}",
        f"push: 1 task(s), e.g. {TEMPLATES['push'].example!r}",
    ]
    assert templates_text({}) == ""
