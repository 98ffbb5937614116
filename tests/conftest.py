"""Shared fixtures. Tests run the real simulator; environments are closed by the tests that build them.

Nothing heavy is imported at module level: the fast layer in `tests/unit` shares this file and must
run without MuJoCo.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import langgap  # noqa: F401  first: it pins the BLAS kernel before anything loads numpy (langgap/blas.py)
from tests.support.harness import SHORT_STEPS, in_ci, tiny_config


@pytest.fixture(scope="session")
def catalog():
    from langgap.catalog.catalog import load_catalog

    return load_catalog("langgap99")


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory):
    """Generated BDDL goes to a per-session cache, never the user's."""
    os.environ["LANGGAP_CACHE"] = str(tmp_path_factory.mktemp("langgap-cache"))


@pytest.fixture(scope="session")
def short_catalog(tmp_path_factory):
    """Three spatial/s0 tasks with a 15-step limit, so harness tests run in seconds."""
    from tests.support.catalogs import cut_down_catalog

    keep = (
        "spatial/s0/black-bowl-1-on-plate",
        "spatial/s0/black-bowl-2-on-plate",
        "spatial/s0/open-cabinet-top-drawer",
    )
    return str(cut_down_catalog(tmp_path_factory.mktemp("catalog") / "short.yaml", keep, steps=SHORT_STEPS))


@pytest.fixture(scope="session")
def tiny_collection(tmp_path_factory) -> Path:
    """Two oracle demonstrations of one spatial task (compact form, with execution noise), collected once."""
    from langgap.demos.collect import collect
    from langgap.engine.spec import ExecutionOptions

    out = tmp_path_factory.mktemp("demos") / "tiny"
    collect(tiny_config(), out, ExecutionOptions(workers=0, progress=False))
    return out


def pytest_runtest_setup(item):
    """`@pytest.mark.requires(available, what)`: skip when `what` is missing, but fail under CI (CI=true),
    where every tool the tests need must be installed (a skipped browser test would pass unnoticed)."""
    for mark in item.iter_markers("requires"):
        available, what = mark.args
        if not available:
            message = f"needs {what}"
            if in_ci():
                pytest.fail(f"{message} (CI=true: a missing tool fails instead of skipping)", pytrace=False)
            pytest.skip(message)
