"""`audit`, the audit as a Python call: LangGap's own catalog gets the sentence check and the recorded reference
findings, says how each ran as it goes, and records only what ran (no simulator)."""

from __future__ import annotations

import json
import shutil

import pytest

from langgap.audit.findings import CHECKS, read_audit
from langgap.audit.run import audit
from langgap.catalog.catalog import registry_path
from langgap.errors import ParameterError

SELECTION = "spatial/s0/*"


@pytest.fixture
def registry(tmp_path):
    """A copy of langgap99's registry and its recorded audit, to record into."""
    shipped = registry_path("langgap99")
    for suffix in (".yaml", ".audit.json"):
        shutil.copy(shipped.with_suffix("").with_suffix(suffix), tmp_path / f"langgap99{suffix}")
    return tmp_path / "langgap99.yaml"


def test_an_own_catalog_gets_the_sentence_check_and_the_recorded_references(registry):
    said = []
    found = audit(str(registry), SELECTION, record=True, progress=said.append)
    assert found.package_ids == () and found.unreadable == ()
    assert found.checked == found.own_ids and len(found.own_ids) == 13
    assert said[0] == "sentence: 13 task(s) by template" and said[-1].startswith("references: recorded for tasks")
    assert set(found.ran) == {"sentence"} and found.recorded == registry.with_name("langgap99.audit.json")
    _, recorded = read_audit(registry)
    ours = {f.task for f in found.findings if f.name in CHECKS["references"]}
    assert ours == {f.task for f in recorded if f.name in CHECKS["references"] and f.task in found.own_ids}
    about = json.loads(found.recorded.read_text())["about"]
    assert about["sentence"]["templates"] == found.ran["sentence"]["templates"]


def test_without_record_nothing_is_written(registry):
    before = registry.with_name("langgap99.audit.json").read_bytes()
    assert audit(str(registry), SELECTION).recorded is None
    assert registry.with_name("langgap99.audit.json").read_bytes() == before


@pytest.mark.parametrize(("given", "message"), [({"starts": -1}, "starts must be"), ({"starts": 1}, "starts checks")])
def test_a_check_that_cannot_run_is_refused_naming_its_parameter(registry, given, message):
    with pytest.raises(ParameterError, match=message) as error:
        audit(str(registry), SELECTION, **given)
    assert error.value.parameters == ("starts",)
