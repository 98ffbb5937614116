"""The commit recorded with results: a verdict just recorded does not make the checkout dirty, code does."""

from __future__ import annotations

import subprocess

from langgap.version import checkout_commit


def _git(root, *args):
    subprocess.run(["git", "-C", str(root), *args], check=True, capture_output=True)


def test_recorded_verdicts_do_not_make_a_checkout_dirty(tmp_path):
    (tmp_path / "registry").mkdir()
    (tmp_path / "oracle.py").write_text("STEPS = 1\n")
    (tmp_path / "registry" / "beyond.gate.json").write_text("{}\n")
    _git(tmp_path, "init", "-q")
    _git(tmp_path, "add", ".")
    _git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "first")
    commit = checkout_commit(tmp_path)
    assert commit and not commit.endswith("-dirty")
    (tmp_path / "registry" / "beyond.gate.json").write_text('{"tasks": {}}\n')
    assert checkout_commit(tmp_path) == commit
    (tmp_path / "oracle.py").write_text("STEPS = 2\n")
    assert checkout_commit(tmp_path) == commit + "-dirty"
    assert checkout_commit(tmp_path / "registry" / "missing") is None
