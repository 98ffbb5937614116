"""Every command a reader copies runs: each ```bash and ```python block of README.md and docs/*.md, a page's
blocks in order in a fresh copy of the repository, each in a fresh shell after `source .venv/bin/activate`,
shrunk by `LANGGAP_SMOKE=1` (which says so on stderr). `tests/support/doc_blocks.py` lists the few blocks that
cannot run here, with the reason, and the pages slow enough to run under -m slow only."""

from __future__ import annotations

import pytest

from tests.support.doc_blocks import PAGES, SLOW_PAGES, run_block, runnable, sandbox
from tests.support.harness import REPO, in_ci

RUN_PAGES = [p for p in PAGES if runnable(p)]


@pytest.mark.parametrize("page", [pytest.param(p, marks=pytest.mark.slow) if p in SLOW_PAGES else p for p in RUN_PAGES])
def test_every_block_of_the_page_runs_as_written(page, tmp_path):
    root = sandbox(tmp_path / "repo")
    for block in runnable(page):
        if ".venv-lerobot/" in block.code and not (REPO / ".venv-lerobot").exists() and not in_ci():
            pytest.skip(f"{block.where} needs .venv-lerobot (./setup.sh without --core makes it)")
        result = run_block(block, root)
        assert result.returncode == 0, (
            f"{block.where}: the {block.language} block exits {result.returncode}\n{block.code}\n"
            f"--- stdout (end)\n{result.stdout[-3000:]}\n--- stderr (end)\n{result.stderr[-3000:]}"
        )
