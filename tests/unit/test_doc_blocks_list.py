"""The docs' tests see every block: each fence names its language, and each block they skip is listed with a
reason and still exists (a stale entry would hide nothing, and a renamed block would silently stop running)."""

from __future__ import annotations

import re

from tests.support.doc_blocks import NOT_RUN, PAGES, RUN_LANGUAGES, SLOW_PAGES, blocks, runnable
from tests.support.harness import REPO


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


def test_no_command_hides_in_an_indented_block():
    """An indented code block is a block the docs' tests do not see: commands go in fenced ones."""
    indented = []
    for page in PAGES:
        fenced = {line for b in blocks(page) for line in range(b.line, b.line + b.code.count("\n") + 2)}
        for number, line in enumerate((REPO / page).read_text().splitlines(), start=1):
            if number not in fenced and line.startswith(("    langgap ", "    ./", "    .venv/")):
                indented.append(f"{page}:{number}")
    assert indented == []


def test_tables_hold_no_escaped_pipe_in_code_and_synopses_fit_the_page():
    """Inside a code span, Markdown keeps `\\|` literally; a usage line past 100 characters scrolls sideways."""
    escaped = [
        f"{page}:{n}"
        for page in PAGES
        for n, line in enumerate((REPO / page).read_text().splitlines(), 1)
        if line.startswith("|") and re.search(r"`[^`]*\\\|[^`]*`", line)
    ]
    assert escaped == []
    synopses = [
        b for page in PAGES for b in blocks(page) if b.language == "text" and b.first_line.startswith("langgap ")
    ]
    assert synopses
    wide = [b.where for b in synopses if max(map(len, b.code.splitlines())) > 100]
    assert wide == []
