"""The code version recorded with every result: the package version plus the git commit when run from a checkout."""

from __future__ import annotations

import functools
import subprocess
from importlib import metadata
from pathlib import Path

# Recorded measurements, not code: a checkout whose only change is a verdict just recorded is not dirty.
MEASUREMENTS = ":(exclude)*.gate.json"


def _git(root: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, timeout=5)


def checkout_commit(root: Path) -> str | None:
    """The commit of the checkout at `root`, with `-dirty` when tracked files other than recorded
    verdicts differ from it; None when `root` is not a checkout git can read."""
    try:
        described = _git(root, "describe", "--always", "--abbrev=12")
        if described.returncode != 0:
            return None
        dirty = _git(root, "diff", "--quiet", "HEAD", "--", ".", MEASUREMENTS).returncode == 1
    except (OSError, subprocess.SubprocessError):
        return None
    return described.stdout.strip() + ("-dirty" if dirty else "")


@functools.cache
def code_version() -> str:
    """`<package version>+<commit>` from a checkout (see `checkout_commit`), else the package version."""
    try:
        version = metadata.version("langgap")
    except metadata.PackageNotFoundError:
        version = "unknown"
    root = Path(__file__).resolve().parents[2]
    # Only LangGap's own checkout: installed into another project's repository, git would name that one's commit.
    commit = checkout_commit(root) if (root / ".git").exists() else None
    return f"{version}+{commit}" if commit else version
