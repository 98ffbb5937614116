"""The layers import downward only: the command line (`cli/`) is the top, and the diagnostics (`diagnostics/`) run
the engine's own code from above it, so no module below them imports them (not even inside a function)."""

from __future__ import annotations

import ast

import pytest

from tests.support.harness import REPO

SRC = REPO / "src" / "langgap"


def _imports(path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    return found | {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}


@pytest.mark.parametrize("upper", ["cli", "diagnostics"])
def test_no_module_below_a_layer_imports_it(upper):
    allowed = {"cli": {"cli"}, "diagnostics": {"cli", "diagnostics"}}[upper]
    below = [p for p in SRC.rglob("*.py") if p.relative_to(SRC).parts[0] not in allowed]
    assert len(below) > 100
    found = [
        f"{path.relative_to(SRC)} imports {name}"
        for path in below
        for name in _imports(path)
        if name == f"langgap.{upper}" or name.startswith(f"langgap.{upper}.")
    ]
    assert not found, found
