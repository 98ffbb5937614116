"""The fenced code blocks of README.md and docs/*.md as a reader copies them, and how the docs' tests run them.

Every ```bash and ```python block is run by `tests/test_doc_blocks.py`, a page's blocks in order in one
directory (a later block may use what an earlier one wrote), each in a fresh shell after
`source .venv/bin/activate`, with `LANGGAP_SMOKE=1` set (`langgap.cli.smoke`: every command shrinks its work
and says how on stderr). A block opened as ```python title="my_policy.py" is a file the reader saves: it is
written under that name, then run. The blocks that cannot run here are listed in `NOT_RUN`, each with the
reason: that list is the one place to review.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from tests.support.harness import REPO

PAGES = ("README.md", *sorted(p.relative_to(REPO).as_posix() for p in (REPO / "docs").glob("*.md")))
RUN_LANGUAGES = ("bash", "python")
FENCE = re.compile(r"^```(?P<info>[^\n`]*)\n(?P<code>.*?)^```[ \t]*$", re.M | re.S)
TITLE = re.compile(r'title="([^"]+)"')
OPENPI_PORT = 8000  # the `openpi` policy's default, as openpi's server's

# (page, the block's first line) -> why the docs' tests do not run it. Keep it short: a block that could run
# with a change of its words should be changed instead.
NOT_RUN: dict[tuple[str, str], str] = {
    ("README.md", "./setup.sh      # install everything, then run the main job"): "CI runs both: .ci/run",
    ("docs/index.md", "./setup.sh      # install everything, then run the main job"): "CI runs both: .ci/run",
    ("docs/development.md", "./test.sh                                  # everything CI runs: both environments, "
     "real simulation"): "the test suite itself (it would run this test)",
    ("docs/development.md", "python -m tools.docs_pictures                          # all three; `report` or "
     "`reflection` for some"): "rewrites the committed pictures from a git worktree of HEAD; "
     "tests/unit/test_docs_pictures.py checks that each is current",
    ("docs/development.md", ".venv/bin/mkdocs serve                     # http://127.0.0.1:8000, rebuilt on every "
     "change"): "a server that runs until stopped; test_docs.py builds the same site with --strict",
    ("docs/evaluation.md", "langgap validate --catalog langgap99 --backend ray --ray-address HEAD:6379 --workers "
     "16 --record"): "joins a Ray cluster at HEAD; tests/test_ray.py runs validate and collect on a two-node "
     "cluster in a network namespace (a head started here would listen beyond 127.0.0.1)",
    ("docs/training.md", ".venv-lerobot/bin/langgap experiment run exp1 --out runs/exp1 --workers 8"):
        "fine-tunes π0.5 (downloaded from the hub) with lerobot-train on a GPU for hours; the rehearsal block "
        "before it runs the same stages with a tiny SmolVLA, test_lerobot_demos.py parses every experiment's "
        "lerobot-train command with LeRobot's own config",
    ("README.md", ".venv-lerobot/bin/langgap eval --policy lerobot --policy-arg path=/ckpts/pi05_libero_finetuned \\"):
        "needs a π0.5 checkpoint and a CUDA GPU; test_lerobot.py runs the lerobot policy on tiny checkpoints",
    ("docs/vla.md", "# ./setup.sh created .venv-lerobot (Python 3.12, lerobot 0.6.1, torch, LangGap, the plugin)"):
        "needs a π0.5 checkpoint and a CUDA GPU; test_lerobot.py runs the lerobot policy on tiny checkpoints",
    ("docs/vla.md", ".venv-lerobot/bin/lerobot-eval --policy.path=/ckpts/smolvla_libero --env.type=langgap \\"):
        "needs a SmolVLA checkpoint; test_lerobot.py runs lerobot-eval --env.type=langgap on a tiny checkpoint",
    ("docs/parity.md", "lerobot-eval --env.type=langgap --env.task='spatial&original' --env.episode_length=280 \\"):
        "needs a checkpoint (--policy.path); test_lerobot.py runs lerobot-eval --env.type=langgap",
}  # fmt: skip
# Blocks that a test of their own runs with `run_block` and whose output it checks too: the docs' runner leaves
# them to it. (page, first line) -> that test.
RUN_BY: dict[tuple[str, str], str] = {
    ("docs/api.md", "import collections"): "tests/test_api.py::test_the_api_page_example_runs_as_printed",
    ("docs/gymnasium.md", "import gymnasium as gym"): "tests/test_gym.py::test_docs_examples_run_as_shown",
}
# Pages whose blocks take minutes even shrunk, or repeat another page's (index.md and vla.md run the README's
# quick start and own policy again): they run under -m slow, the others in CI.
SLOW_PAGES = frozenset({"docs/index.md", "docs/vla.md", "docs/catalogs.md", "docs/training.md", "docs/results.md"})


@dataclass(frozen=True)
class Block:
    """One fenced block: the page and line it opens on, its language, its title (a file name) and its code."""

    page: str
    line: int
    language: str
    title: str | None
    code: str

    @property
    def first_line(self) -> str:
        return self.code.splitlines()[0] if self.code.strip() else ""

    @property
    def where(self) -> str:
        return f"{self.page}:{self.line}"


def blocks(page: str) -> list[Block]:
    """Every fenced block of `page` (a path relative to the repository), in order."""
    text = (REPO / page).read_text(encoding="utf-8")
    found = []
    for match in FENCE.finditer(text):
        info = match["info"].strip()
        title = TITLE.search(info)
        found.append(
            Block(
                page=page,
                line=text.count("\n", 0, match.start()) + 1,
                language=info.split()[0] if info else "",
                title=title.group(1) if title else None,
                code=match["code"],
            )
        )
    return found


def runnable(page: str) -> list[Block]:
    """The blocks of `page` the docs' runner runs: bash and python, less `NOT_RUN` and `RUN_BY`."""
    left = NOT_RUN.keys() | RUN_BY.keys()
    return [b for b in blocks(page) if b.language in RUN_LANGUAGES and (page, b.first_line) not in left]


def sandbox(destination: Path) -> Path:
    """A copy of the repository's files (tracked, or new and not ignored) at `destination`, with its environments
    linked in: a page's blocks write their runs, and `--record` its verdicts, here and never into the checkout."""
    listed = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=REPO,
        capture_output=True,
        check=True,
        text=True,
    ).stdout.split("\0")
    for name in filter(None, listed):
        source = REPO / name
        if source.is_file():
            target = destination / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target)
    for venv in (".venv", ".venv-lerobot"):
        if (REPO / venv).exists():
            (destination / venv).symlink_to(REPO / venv)
    return destination


def block_environment(root: Path) -> dict[str, str]:
    """The environment a block runs in: the user's, with `LANGGAP_SMOKE=1` and the sandbox's code first."""
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONHOME")}
    env["LANGGAP_SMOKE"] = "1"
    # The environments' editable install points at the checkout; the sandbox's copy must be what runs.
    env["PYTHONPATH"] = str(root / "src")
    return env


# `langgap validate` exits 1 when a task is not shown doable or a claim fails: an answer, not a broken command
# (on one shrunk init state it is likely). The blocks run with this function in front of them, so that this
# exit 1 of validate continues the block; a traceback, or any other non-zero exit, still stops it and fails.
VALIDATE_ANSWERS = """langgap() {
    local status=0 err
    err=$(mktemp)
    command langgap "$@" 2>"$err" || status=$?
    cat "$err" >&2
    if [ "$status" = 1 ] && [ "${1:-}" = validate ] && ! grep -q '^Traceback' "$err"; then status=0; fi
    rm -f "$err"
    return "$status"
}
"""


def command(block: Block) -> list[str]:
    """The shell command that runs `block` as a reader would, after `source .venv/bin/activate`."""
    if block.language == "python":
        script = block.title or f".doc-block-{block.line}.py"
        return ["bash", "-c", f'source .venv/bin/activate && set -euo pipefail && python "{script}"']
    # -u: a variable only some other shell defines fails here, as the reader's command would misbehave there.
    return ["bash", "-c", "source .venv/bin/activate && set -euo pipefail\n" + VALIDATE_ANSWERS + block.code]


@contextlib.contextmanager
def services(block: Block, root: Path) -> Iterator[None]:
    """What `block` needs running beside it: for `--policy openpi`, a stand-in for openpi's policy server on the
    port the block names, else the policy's default (openpi's own `WebsocketPolicyServer` answering no-op chunks;
    tests/support/openpi_servers.py)."""
    if "--policy openpi" not in block.code:
        yield
        return
    port = re.search(r"--policy-arg port=(\d+)", block.code)
    port = port.group(1) if port else str(OPENPI_PORT)
    record = root / ".openpi-requests"
    record.mkdir(exist_ok=True)
    env = {**os.environ, "RECORD_DIR": str(record), "PYTHONPATH": os.pathsep.join([str(REPO / "src"), str(REPO)])}
    server = subprocess.Popen(
        [sys.executable, "-m", "tests.support.openpi_servers", "openpi-record", port],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        _wait_healthy(int(port))
        yield
    finally:
        server.kill()
        server.wait()


def _wait_healthy(port: int, timeout_s: float = 60) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        with contextlib.suppress(OSError), urllib.request.urlopen(f"http://127.0.0.1:{port}/healthz", timeout=2) as r:
            if r.status == 200:
                return
        time.sleep(0.2)
    raise TimeoutError(f"no server on 127.0.0.1:{port} after {timeout_s:.0f} s")


def run_block(block: Block, root: Path, timeout_s: float = 1200) -> subprocess.CompletedProcess:
    """Run one block in the sandbox `root`."""
    if block.language == "python":
        (root / (block.title or f".doc-block-{block.line}.py")).write_text(block.code, encoding="utf-8")
    with services(block, root):
        return subprocess.run(
            command(block),
            cwd=root,
            env=block_environment(root),
            capture_output=True,
            text=True,
            timeout=timeout_s,
        )
