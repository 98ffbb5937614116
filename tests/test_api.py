"""The public API: `import langgap` is cheap, every exported name resolves and is documented, and
the Python API page's example (docs/api.md) runs as printed."""

from __future__ import annotations

import os
import subprocess
import sys

from tests.support.doc_blocks import blocks, run_block, sandbox
from tests.support.harness import REPO


def _python(code: str, cwd=None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "src"), str(REPO)])}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=cwd, timeout=900)


def test_import_is_cheap_and_every_name_resolves_with_a_docstring():
    result = _python(
        "import sys, langgap\n"
        "assert 'mujoco' not in sys.modules and 'langgap.engine' not in sys.modules\n"
        "for name in langgap.__all__:\n"
        "    value = getattr(langgap, name)\n"
        "    assert (value.__doc__ or '').strip(), name\n"
        "    assert name in dir(langgap)\n"
        "print(len(langgap.__all__))\n"
        "try:\n"
        "    langgap.EvalConfig\n"
        "except AttributeError as exc:\n"
        "    print(exc)\n"
    )
    assert result.returncode == 0, result.stderr
    count, missing = result.stdout.splitlines()
    assert int(count) >= 15 and missing == "module 'langgap' has no attribute 'EvalConfig'"


def test_the_api_page_example_runs_as_printed(tmp_path):
    (block,) = [b for b in blocks("docs/api.md") if b.language == "python"]
    assert len(block.code.strip().splitlines()) <= 12
    root = sandbox(tmp_path / "repo")
    result = run_block(block, root)
    assert result.returncode == 0, result.stderr[-3000:]
    assert result.stdout.splitlines() == ["1/13 episodes succeeded", "Counter({'did_source_task': 12})"]
    assert (root / "runs" / "api" / "episodes.sqlite").exists()
