"""The figures README.md and docs/*.md take from the registries and stored audits, written in by the code that counts.

A region of a page between `<!-- generated: WHAT -->` and `<!-- /generated -->` holds what WHAT gives:

* `verdicts CATALOG`: the catalog's gate verdicts in one phrase ("848 tasks: 621 doable, 227 unproven"), counted
  by `langgap.gate.coverage`, as `langgap tasks gate` counts them; it fits inside a sentence or a table cell;
* `langgap tasks ARGS` (read-only: `gate`, `audit` without `--starts`, `--references`, `--record` or `--html`,
  `list`, `show`): what that command prints, run in process; a Markdown table as it is, any other text in a
  ```text block.

    python -m tools.docs_counts            # rewrite every region (from the repository root)
    python -m tools.docs_counts --check    # exit 1 naming each region that is not current

`tests/test_docs_counts.py` runs the check, so a re-gate or a new audit that moves a figure fails the tests
until the pages say it.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import re
import shlex
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PAGES = ("README.md", *sorted(p.relative_to(REPO).as_posix() for p in (REPO / "docs").glob("*.md")))
# A marker quoted in a code span (as the development page quotes it) is text, not a region.
REGION = re.compile(r"(?<!`)<!-- generated: (?P<what>[^>]*?) -->(?P<body>.*?)<!-- /generated -->", re.S)
READ_ONLY = ("gate", "audit", "list", "show")


class CountsError(Exception):
    """A region names something that cannot be generated."""


def verdicts_phrase(catalog_name: str) -> str:
    """The catalog's verdicts in one phrase: its tasks, then each verdict that some task has, then the ungated."""
    from langgap.catalog.catalog import load_catalog
    from langgap.gate.coverage import gate_counts

    (total,) = [c for c in gate_counts(load_catalog(catalog_name).select("all")) if c.dimension == "all"]
    parts = [f"{n:,} {verdict}" for verdict, n in total.verdicts.items() if n]
    if total.tasks > total.gated:
        parts.append(f"{total.tasks - total.gated:,} not gated")
    return f"{total.tasks:,} tasks: {', '.join(parts)}"


@contextlib.contextmanager
def _unshrunk() -> Iterator[None]:
    """The real figures, even where `LANGGAP_SMOKE` is set (the docs' tests run this tool as a page shows it)."""
    from langgap.cli.smoke import ENV

    saved = os.environ.pop(ENV, None)
    try:
        yield
    finally:
        if saved is not None:
            os.environ[ENV] = saved


def command_output(argv: list[str]) -> str:
    """What `langgap tasks …` prints, run in this process."""
    from langgap.cli.main import main

    if argv[:2] != ["langgap", "tasks"] or len(argv) < 3 or argv[2] not in READ_ONLY:
        raise CountsError(f"not a read-only `langgap tasks` command: {shlex.join(argv)}")
    if argv[2] == "audit" and ({"--starts", "--references", "--record", "--html"} & set(argv)):
        raise CountsError(f"an audit that simulates or records: {shlex.join(argv)}")
    out = io.StringIO()
    with contextlib.redirect_stdout(out), _unshrunk():
        code = main(argv[1:])
    if code:
        raise CountsError(f"{shlex.join(argv)} exited {code}")
    return out.getvalue().rstrip("\n")


def generate(what: str) -> str:
    """The text a region naming `what` holds (between its markers)."""
    argv = shlex.split(what)
    if argv[:1] == ["verdicts"] and len(argv) == 2:
        return verdicts_phrase(argv[1])
    if argv[:1] == ["langgap"]:
        output = command_output(argv)
        body = output if output.startswith("|") else f"```text\n{output}\n```"
        return f"\n{body}\n"
    raise CountsError(f"unknown generated region {what!r} (verdicts CATALOG, or langgap tasks …)")


def rewrite(text: str, make: Callable[[str], str] = generate) -> str:
    """`text` with every region's body replaced by what it names."""
    return REGION.sub(lambda m: f"<!-- generated: {m['what']} -->{make(m['what'])}<!-- /generated -->", text)


def stale_regions(root: Path = REPO) -> list[str]:
    """`page: what` for each region whose body is not what it names."""
    cache: dict[str, str] = {}

    def make(what: str) -> str:
        if what not in cache:
            cache[what] = generate(what)
        return cache[what]

    stale = []
    for page in PAGES:
        for match in REGION.finditer((root / page).read_text(encoding="utf-8")):
            if match["body"] != make(match["what"]):
                stale.append(f"{page}: {match['what']}")
    return stale


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.docs_counts", description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only say which regions are not current (exit 1)")
    args = parser.parse_args(argv)
    if args.check:
        stale = stale_regions()
        for region in stale:
            print(f"not current: {region}")
        return 1 if stale else 0
    for page in PAGES:
        path = REPO / page
        text = path.read_text(encoding="utf-8")
        if (new := rewrite(text)) != text:
            path.write_text(new, encoding="utf-8")
            print(f"wrote {page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
