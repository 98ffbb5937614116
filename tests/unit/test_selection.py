"""The task-selection grammar, checked against counts read from the registry file itself."""

from __future__ import annotations

import fnmatch
from collections import Counter
from pathlib import Path

import pytest
import yaml

from langgap.catalog.catalog import load_catalog
from langgap.errors import LangGapError

REGISTRY = Path(__file__).parents[2] / "src/langgap/catalog/registry/langgap99.yaml"
ENTRIES = yaml.safe_load(REGISTRY.read_text())["tasks"]
IDS = [e["id"] for e in ENTRIES]


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap99")


def ids(catalog, expression):
    return [t.id for t in catalog.select(expression)]


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


def test_results_keep_catalog_order_and_the_default_is_the_feasible_tasks(catalog):
    chosen = ids(catalog, "heldout,original")
    assert chosen == [i for i in IDS if i in set(chosen)]
    assert ids(catalog, None) == ids(catalog, "") == ids(catalog, "feasible")
    assert set(ids(catalog, "feasible")) | set(ids(catalog, "infeasible")) == set(IDS)


@pytest.mark.parametrize(
    ("expression", "message"),
    [
        ("spatial/s0/levitate", "spatial/s0/levitate"),
        ("nothing*", "matches no task"),
        ("paper:x", "paper id must be a number"),
        ("spatial&libero10", "matches no task"),
    ],
)
def test_a_term_that_matches_nothing_is_one_clear_error(catalog, expression, message):
    with pytest.raises(LangGapError, match=message) as info:
        catalog.select(expression)
    assert "\n" not in str(info.value)
