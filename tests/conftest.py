"""Shared fixtures. Tests run the real simulator; environments are closed by the tests that build them.

Nothing heavy is imported at module level: the fast layer in `tests/unit` shares this file and must
run without MuJoCo.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHORT_STEPS = 15


@pytest.fixture(scope="session")
def catalog():
    from langgap.catalog.catalog import load_catalog

    return load_catalog("langgap99")


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory):
    """Generated BDDL goes to a per-session cache, never the user's."""
    os.environ["LANGGAP_CACHE"] = str(tmp_path_factory.mktemp("langgap-cache"))


def store_rows(run: Path) -> list[dict]:
    """Every episode row of a run store, as plain dicts, in key order."""
    import sqlite3

    db = sqlite3.connect(Path(run) / "episodes.sqlite")
    db.row_factory = sqlite3.Row
    rows = [dict(r) for r in db.execute("SELECT * FROM episodes ORDER BY task_id, init_index, condition")]
    db.close()
    return rows


def run_cli(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """Run `langgap ARGS` in a fresh interpreter, as a user would."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "src"), str(REPO)])}
    return subprocess.run(
        [sys.executable, "-m", "langgap.cli.main", *args], capture_output=True, text=True, timeout=timeout, env=env
    )


@pytest.fixture(scope="session")
def short_catalog(tmp_path_factory):
    """Three spatial/s0 tasks with a 15-step limit, so harness tests run in seconds."""
    import yaml

    source = yaml.safe_load((REPO / "src/langgap/catalog/registry/langgap99.yaml").read_text())
    keep = {
        "spatial/s0/black-bowl-1-on-plate",
        "spatial/s0/black-bowl-2-on-plate",
        "spatial/s0/open-cabinet-top-drawer",
    }
    data = {
        "catalog": "short",
        "max_steps": {"libero_spatial": SHORT_STEPS},
        "tasks": [t for t in source["tasks"] if t["id"] in keep],
    }
    path = tmp_path_factory.mktemp("catalog") / "short.yaml"
    path.write_text(yaml.safe_dump(data))
    return str(path)


TINY_TASK = "spatial/s0/black-bowl-1-on-plate"


def tiny_config():
    """The collection settings of `tiny_collection` (two noisy oracle demonstrations of TINY_TASK)."""
    from langgap.demos.collect import CollectConfig

    return CollectConfig(catalog="langgap99", tasks=(TINY_TASK,), demos=2, seed=7, noise=0.2)


@pytest.fixture(scope="session")
def tiny_collection(tmp_path_factory) -> Path:
    """Two oracle demonstrations of one spatial task (compact form, with execution noise), collected once."""
    from langgap.demos.collect import collect

    out = tmp_path_factory.mktemp("demos") / "tiny"
    collect(tiny_config(), out, workers=0, progress=False)
    return out
