"""The task-selection grammar, checked against counts read from the registry file itself."""

from __future__ import annotations

import fnmatch
import json
from collections import Counter
from pathlib import Path

import pytest
import yaml

from langgap.catalog.catalog import catalog_from_data, load_catalog
from langgap.errors import LangGapError

REGISTRY = Path(__file__).parents[2] / "src/langgap/catalog/registry/langgap99.yaml"
ENTRIES = yaml.safe_load(REGISTRY.read_text())["tasks"]
IDS = [e["id"] for e in ENTRIES]
# The recorded feasibility verdicts, read directly (the catalog reads them through `read_verdicts`): every
# langgap99 task passes its gate, so rejection is checked on the `full` catalog's.
VERDICTS = json.loads(REGISTRY.with_suffix(".gate.json").read_text())["tasks"]
REJECTED = {i for i, v in VERDICTS.items() if not v["feasible"]}
FULL = REGISTRY.with_name("full.yaml")
FULL_IDS = [e["id"] for e in yaml.safe_load(FULL.read_text())["tasks"]]
FULL_REJECTED = {
    i for i, v in json.loads(FULL.with_suffix(".gate.json").read_text())["tasks"].items() if not v["feasible"]
}
SHORT = {"libero_spatial": "spatial", "libero_object": "object", "libero_goal": "goal", "libero_10": "libero10"}


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap99")


def ids(catalog, expression):
    return [t.id for t in catalog.select(expression)]


def where(**attributes) -> list[str]:
    """The registry's ids whose entries have every given attribute value, in file order."""
    return [e["id"] for e in ENTRIES if all(e.get(k) == v for k, v in attributes.items())]


def test_terms_select_what_the_registry_says(catalog):
    suites = Counter(e["suite"] for e in ENTRIES)
    assert len(ids(catalog, "all")) == len(IDS) == 99
    assert len(ids(catalog, "libero_spatial")) == len(ids(catalog, "spatial")) == suites["libero_spatial"]
    assert len(ids(catalog, "libero10")) == suites["libero_10"]
    assert len(ids(catalog, "original")) == sum(e["kind"] == "original" for e in ENTRIES) == 40
    assert len(ids(catalog, "extended")) == 59
    assert len(ids(catalog, "change_target")) == sum(e.get("dimension") == "change_target" for e in ENTRIES)
    assert len(ids(catalog, "train")) == sum(e.get("split") == "train" for e in ENTRIES) == 16
    assert ids(catalog, "spatial/s0/*") == [i for i in IDS if fnmatch.fnmatchcase(i, "spatial/s0/*")]
    paper_0 = next(e["id"] for e in ENTRIES if e.get("paper_id") == 0)
    assert ids(catalog, "paper:0") == [paper_0]


@pytest.mark.parametrize(
    ("suite", "count"), [("libero_spatial", 38), ("libero_object", 32), ("libero_goal", 19), ("libero_10", 10)]
)
def test_a_suite_by_its_long_or_short_name(catalog, suite, count):
    assert ids(catalog, suite) == ids(catalog, SHORT[suite]) == where(suite=suite)
    assert len(where(suite=suite)) == count


@pytest.mark.parametrize(
    ("term", "attribute", "count"),
    [
        ("original", "kind", 40),
        ("extended", "kind", 59),
        ("change_object", "dimension", 38),
        ("change_target", "dimension", 13),
        ("spatial_description", "dimension", 5),
        ("drawer_action", "dimension", 3),
        ("train", "split", 16),
        ("heldout", "split", 43),
    ],
)
def test_a_kind_dimension_or_split_is_the_registry_field(catalog, term, attribute, count):
    assert ids(catalog, term) == where(**{attribute: term})
    assert len(ids(catalog, term)) == count


def test_ids_globs_and_paper_numbers(catalog):
    assert ids(catalog, "goal/s7/turn-on-stove") == ["goal/s7/turn-on-stove"]
    for pattern in ("spatial/s?/*", "*/s0/*-on-plate", "object/s[0-2]/*", "*drawer*"):
        expected = [i for i in IDS if fnmatch.fnmatchcase(i, pattern)]
        assert expected and ids(catalog, pattern) == expected
    for number in (0, 17, 40, 98):
        (expected,) = [e["id"] for e in ENTRIES if e.get("paper_id") == number]
        assert ids(catalog, f"paper:{number}") == [expected]
    assert ids(catalog, "langgap99") == IDS  # every task of the paper's own catalog


def test_the_default_is_the_tasks_the_gate_did_not_reject(catalog):
    assert not REJECTED and ids(catalog, None) == ids(catalog, "feasible") == IDS  # every langgap99 task passed
    with pytest.raises(LangGapError, match="selection 'rejected' matches no task"):
        ids(catalog, "rejected")
    full = load_catalog("full")
    assert 0 < len(FULL_REJECTED) < len(FULL_IDS)
    feasible = [i for i in FULL_IDS if i not in FULL_REJECTED]
    assert ids(full, "feasible") == feasible
    assert ids(full, None) == ids(full, "") == ids(full, "  ") == feasible
    assert ids(full, "rejected") == [i for i in FULL_IDS if i in FULL_REJECTED]
    # a rejected task is still selectable by id or by a term that does not ask about feasibility
    chosen = sorted(FULL_REJECTED)[0]
    assert ids(full, chosen) == [chosen] and chosen in ids(full, "all")


def test_union_intersection_and_exclusion(catalog):
    spatial = set(ids(catalog, "spatial"))
    heldout = set(ids(catalog, "heldout"))
    assert set(ids(catalog, "spatial&heldout")) == spatial & heldout
    assert set(ids(catalog, "spatial,heldout")) == spatial | heldout
    s0 = set(ids(catalog, "spatial/s0/*"))
    assert set(ids(catalog, "spatial&!spatial/s0/*")) == spatial - s0
    assert set(ids(catalog, "!spatial")) == set(IDS) - spatial
    assert ids(catalog, "goal/s1/*,paper:0") == [
        i for i in IDS if i in set(ids(catalog, "goal/s1/*")) | set(ids(catalog, "paper:0"))
    ]


def test_combined_terms_against_the_registry(catalog):
    assert ids(catalog, "spatial&heldout") == where(suite="libero_spatial", split="heldout")
    assert ids(catalog, "goal&extended&change_object") == where(
        suite="libero_goal", kind="extended", dimension="change_object"
    )
    assert ids(catalog, "original&!spatial/s0/*") == [
        i for i in where(kind="original") if not fnmatch.fnmatchcase(i, "spatial/s0/*")
    ]
    assert ids(catalog, "!original&!heldout") == where(split="train")  # two exclusions from all tasks
    assert ids(catalog, "feasible&!rejected") == ids(catalog, "feasible")
    # spaces around terms and operators are ignored, an empty union member is skipped
    assert ids(catalog, " spatial & heldout , , libero10 ") == [
        i for i in IDS if i in set(where(suite="libero_spatial", split="heldout")) | set(where(suite="libero_10"))
    ]


def test_results_keep_catalog_order_without_duplicates(catalog):
    chosen = ids(catalog, "heldout,original")
    assert chosen == [i for i in IDS if i in set(chosen)]
    assert ids(catalog, "libero10,spatial/s0/*,paper:0,spatial/s0/black-bowl-1-on-plate") == [
        i for i in IDS if i.startswith("spatial/s0/") or i.startswith("libero10/")
    ]
    both = [e["id"] for e in ENTRIES if e["suite"] in ("libero_goal", "libero_10")]  # interleaved in the file
    assert ids(catalog, "libero10,goal") == ids(catalog, "goal,libero10") == both
    assert both != where(suite="libero_goal") + where(suite="libero_10")
    full = load_catalog("full")
    assert set(ids(full, "feasible")) | set(ids(full, "rejected")) == set(FULL_IDS)


@pytest.mark.parametrize(
    ("expression", "message"),
    [
        ("spatial/s0/levitate", "unknown task 'spatial/s0/levitate'"),
        ("nothing*", "selection term 'nothing\\*' matches no task"),
        ("paper:x", "paper id must be a number: 'paper:x'"),
        ("paper:500", "selection term 'paper:500' matches no task"),
        ("spatial&libero10", "selection 'spatial&libero10' matches no task"),
        ("spatial,frobnicate", "unknown task 'frobnicate'"),
        ("spatial&!spatial", "selection 'spatial&!spatial' matches no task"),
        ("!all", "selection '!all' matches no task"),
    ],
)
def test_a_term_that_matches_nothing_is_one_clear_error(catalog, expression, message):
    with pytest.raises(LangGapError, match=message) as info:
        catalog.select(expression)
    assert "\n" not in str(info.value)


def test_a_near_miss_id_gets_suggestions(catalog):
    with pytest.raises(LangGapError, match="did you mean spatial/s0/ramekin-on-plate"):
        catalog.select("spatial/s0/ramekin-on-plat")
    with pytest.raises(LangGapError, match="all, feasible, rejected, langgap99"):  # the keywords are listed
        catalog.select("spatial/s9/*-on-moon")


def test_a_term_that_is_no_id_nor_glob_is_an_unknown_task_and_paper_takes_one_number():
    catalog = load_catalog("langgap99")
    with pytest.raises(LangGapError, match="^unknown task 'Xylophone' in catalog langgap99"):
        catalog.select("Xylophone")
    with pytest.raises(LangGapError, match="^paper id must be a number: 'paper:3:4'$"):
        catalog.select("paper:3:4")


def test_langgap99_in_a_catalog_without_its_tasks_names_the_term():
    data = yaml.safe_load(REGISTRY.read_text())
    data["catalog"] = "mine"
    data["tasks"] = [e | {"in_langgap99": False} for e in data["tasks"]]
    with pytest.raises(LangGapError, match="^selection term 'langgap99' matches no task in catalog mine"):
        catalog_from_data(data).select("langgap99")
