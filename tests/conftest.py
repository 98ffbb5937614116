"""Shared fixtures. Tests run the real simulator; environments are closed by the tests that build them."""

from __future__ import annotations

import subprocess
import sys

import pytest

from langgap.catalog.catalog import load_catalog


@pytest.fixture(scope="session")
def catalog():
    return load_catalog("langgap99")


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory):
    """Generated BDDL goes to a per-session cache, never the user's."""
    import os

    os.environ["LANGGAP_CACHE"] = str(tmp_path_factory.mktemp("langgap-cache"))


def run_cli(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """Run `langgap ARGS` in a fresh interpreter, as a user would."""
    return subprocess.run(
        [sys.executable, "-m", "langgap.cli.main", *args], capture_output=True, text=True, timeout=timeout
    )
