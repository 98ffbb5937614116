"""`@pytest.mark.requires`: a missing tool skips a test on a workstation and fails it under CI (CI=true)."""

from __future__ import annotations

import os
import subprocess
import sys

from tests.support.harness import REPO

TEST = """
import pytest

@pytest.mark.requires(False, "a tool nobody has")
def test_needs_the_tool():
    pass
"""


def _run(tmp_path, ci: str) -> subprocess.CompletedProcess:
    (tmp_path / "test_tool.py").write_text(TEST)
    env = {**os.environ, "CI": ci, "PYTHONPATH": str(REPO)}
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "tests.conftest",
         "-c", str(REPO / "pyproject.toml"), "--rootdir", str(REPO), str(tmp_path / "test_tool.py")],
        capture_output=True, text=True, env=env, cwd=REPO,
    )  # fmt: skip


def test_a_missing_tool_skips_outside_ci(tmp_path):
    result = _run(tmp_path, "")
    assert result.returncode == 0 and "1 skipped" in result.stdout, result.stdout


def test_a_missing_tool_fails_under_ci(tmp_path):
    result = _run(tmp_path, "true")
    assert result.returncode == 1 and "CI=true" in result.stdout, result.stdout
