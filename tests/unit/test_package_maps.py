"""A package's map names every module it holds: its docstring, its row of docs/development.md's layer table,
and docs/api.md's table of its modules. A module added without a line there is found here."""

from __future__ import annotations

import importlib
import re

import pytest

from tests.support.harness import REPO

SRC = REPO / "src" / "langgap"


def _modules(package: str) -> set[str]:
    return {p.stem for p in (SRC / package).glob("*.py") if p.stem != "__init__"}


def _quoted(text: str) -> set[str]:
    return set(re.findall(r"`\.?(\w+)`", text))


def _layer_row(package: str) -> str:
    development = (REPO / "docs" / "development.md").read_text()
    return next(line for line in development.splitlines() if line.startswith(f"| `{package}/` |"))


def _api_rows(package: str) -> set[str]:
    """The modules docs/api.md's tables name in their first column (`langgap.audit.findings`, `.sentences`)."""
    named = set()
    for line in (REPO / "docs" / "api.md").read_text().splitlines():
        first = line.split("|")[1] if line.startswith("|") else ""
        if f"langgap.{package}." in first:
            named |= set(re.findall(rf"langgap\.{package}\.(\w+)", first)) | set(re.findall(r"`\.(\w+)`", first))
    return named


@pytest.mark.parametrize(("package", "on_api_page"), [("gate", True), ("audit", True), ("diagnostics", False)])
def test_every_module_of_a_package_is_on_its_maps(package, on_api_page):
    modules = _modules(package)
    assert modules
    docstring = importlib.import_module(f"langgap.{package}").__doc__ or ""
    assert sorted(modules - _quoted(docstring)) == [], "not in the package's docstring"
    assert sorted(modules - _quoted(_layer_row(package))) == [], "not in docs/development.md's layer row"
    if on_api_page:
        assert sorted(modules - _api_rows(package)) == [], "not in docs/api.md's table"
