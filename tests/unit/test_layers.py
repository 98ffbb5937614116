"""The layers import downward only: the command line (`cli/`) is the top, and the diagnostics (`diagnostics/`) run
the engine's own code from above it; the gate (`gate/`) runs its work through the engine, and the audit
(`audit/`) checks the catalog's tasks, each beside the other and never importing it. No module below a layer
imports it (not even inside a function)."""

from __future__ import annotations

import ast

import pytest

from tests.support.harness import REPO

SRC = REPO / "src" / "langgap"


def _imports(path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    return found | {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}


# A layer -> the packages that may import it: itself and those above it. The registry generators use the audit's
# findings (on the files they leave out, on a trial that repeats another's); the doctor counts the gate's verdicts.
ABOVE = {
    "cli": {"cli"},
    "diagnostics": {"cli", "diagnostics"},
    "gate": {"cli", "diagnostics", "gate"},
    "audit": {"cli", "generation", "audit"},
}


@pytest.mark.parametrize("upper", sorted(ABOVE))
def test_no_module_below_a_layer_imports_it(upper):
    allowed = ABOVE[upper]
    below = [p for p in SRC.rglob("*.py") if p.relative_to(SRC).parts[0] not in allowed]
    assert len(below) > 100
    found = [
        f"{path.relative_to(SRC)} imports {name}"
        for path in below
        for name in _imports(path)
        if name == f"langgap.{upper}" or name.startswith(f"langgap.{upper}.")
    ]
    assert not found, found
