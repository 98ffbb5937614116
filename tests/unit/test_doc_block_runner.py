"""The docs' runner itself (`tests/support/doc_blocks.py`): a block whose command fails fails, wherever the failure
is, and the one non-zero exit it lets through is `langgap validate`'s answer (exit 1 without a traceback)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.doc_blocks import Block, run_block
from tests.support.harness import REPO

# A stand-in `langgap` first on the PATH: it prints its arguments and exits with the status the block passes it
# in LANGGAP_EXIT (a traceback first when LANGGAP_TRACEBACK is set). The real `langgap validate` takes minutes
# to give its exit 1; what is tested here is what the runner makes of each exit.
STAND_IN = """mkdir -p bin
cat > bin/langgap <<'EOF'
#!/usr/bin/env bash
echo "langgap $*"
if [ -n "${LANGGAP_TRACEBACK:-}" ]; then echo 'Traceback (most recent call last):' >&2; fi
exit "${LANGGAP_EXIT:-0}"
EOF
chmod +x bin/langgap
PATH="$PWD/bin:$PATH"
"""


@pytest.fixture
def root(tmp_path) -> Path:
    """The smallest directory a block runs in: the environment the runner activates, and nothing else."""
    (tmp_path / ".venv").symlink_to(REPO / ".venv")
    return tmp_path


def _bash(code: str) -> Block:
    return Block(page="docs/page.md", line=3, language="bash", title=None, code=code)


def _python(code: str, title: str | None = None) -> Block:
    return Block(page="docs/page.md", line=7, language="python", title=title, code=code)


def test_a_bash_block_that_succeeds_passes_with_its_output(root):
    result = run_block(_bash("echo one\necho two\n"), root)
    assert (result.returncode, result.stdout) == (0, "one\ntwo\n")


@pytest.mark.parametrize(
    ("failing", "status"),
    [
        ("false", 1),  # -e: a failing command in the middle stops the block
        ("false | cat", 1),  # pipefail: a pipeline fails when any of its commands does
        ('echo "$LANGGAP_UNSET_IN_EVERY_SHELL"', 0),  # -u: a variable the block never set
        ("langgap eval --policy oracle", 1),  # exit 1 of a command that is not validate
        ("langgap validate --catalog langgap99", 2),  # validate's exit 2: a broken command, not an answer
        ("LANGGAP_TRACEBACK=1 langgap validate --catalog langgap99", 1),  # validate's exit 1 after a traceback
    ],
)
def test_a_bash_block_fails_at_a_failing_command_in_its_middle(root, failing, status):
    code = f"{STAND_IN}export LANGGAP_EXIT={status}\necho before\n{failing}\necho after\n"
    result = run_block(_bash(code), root)
    assert result.returncode != 0, result.stdout
    assert "before" in result.stdout and "after" not in result.stdout


def test_validates_exit_1_without_a_traceback_is_an_answer_and_the_block_goes_on(root):
    code = f"{STAND_IN}export LANGGAP_EXIT=1\nlanggap validate --catalog langgap99\necho after\n"
    result = run_block(_bash(code), root)
    assert result.returncode == 0, result.stderr
    assert result.stdout == "langgap validate --catalog langgap99\nafter\n"


def test_a_python_block_that_raises_fails_and_one_that_runs_passes(root):
    raising = run_block(_python("print('before')\nraise SystemError('the block broke')\nprint('after')\n"), root)
    assert raising.returncode != 0 and raising.stdout == "before\n"
    assert raising.stderr.rstrip().endswith("SystemError: the block broke")
    passing = run_block(_python("print('ran')\n", title="my_policy.py"), root)
    assert (passing.returncode, passing.stdout) == (0, "ran\n")
    assert (root / "my_policy.py").read_text() == "print('ran')\n"  # a titled block is the file the reader saves
