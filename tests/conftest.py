"""Shared fixtures. Tests run the real simulator; environments are closed by the tests that build them."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from langgap.catalog.catalog import load_catalog

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def catalog():
    return load_catalog("langgap99")


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory):
    """Generated BDDL goes to a per-session cache, never the user's."""
    os.environ["LANGGAP_CACHE"] = str(tmp_path_factory.mktemp("langgap-cache"))


def run_cli(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """Run `langgap ARGS` in a fresh interpreter, as a user would."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.run(
        [sys.executable, "-m", "langgap.cli.main", *args], capture_output=True, text=True, timeout=timeout, env=env
    )
