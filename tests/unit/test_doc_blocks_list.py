"""The docs' tests see every block: each fence names its language, and each block they skip is listed with a
reason and still exists (a stale entry would hide nothing, and a renamed block would silently stop running)."""

from __future__ import annotations

from tests.support.doc_blocks import NOT_RUN, PAGES, RUN_LANGUAGES, SLOW_PAGES, blocks, runnable


def test_every_fence_names_its_language():
    unnamed = [b.where for page in PAGES for b in blocks(page) if not b.language]
    assert unnamed == []


def test_commands_live_in_bash_blocks_not_in_text_ones():
    """A `text` block shows output or a synopsis; a command line a reader copies belongs in a bash block."""
    hidden = [
        b.where
        for page in PAGES
        for b in blocks(page)
        if b.language == "text" and any(line.startswith(("langgap ", "./", ".venv")) and "[" not in line
                                        for line in b.code.splitlines())
    ]  # fmt: skip
    assert hidden == []


def test_every_skipped_block_exists_and_says_why():
    present = {(b.page, b.first_line) for page in PAGES for b in blocks(page) if b.language in RUN_LANGUAGES}
    assert sorted(set(NOT_RUN) - present) == []
    assert all(len(reason) > 20 for reason in NOT_RUN.values())
    assert set(PAGES) >= SLOW_PAGES


def test_the_readme_quick_start_is_run():
    commands = "".join(b.code for b in runnable("README.md"))
    assert "langgap eval --policy oracle" in commands and "langgap report" in commands
