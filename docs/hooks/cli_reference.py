"""MkDocs hook: the CLI reference page, generated at build time from `langgap.cli.main`'s argparse parsers.

A page that holds the line `<!-- langgap-cli-reference -->` gets it replaced by one section per command
(and per sub-command): its help, its usage line and a table of its arguments with their defaults and
choices. The parsers are the only source, so a new flag appears in the docs without editing them.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

MARKER = "<!-- langgap-cli-reference -->"
_SRC = Path(__file__).resolve().parents[2] / "src"


def build_parser() -> argparse.ArgumentParser:
    """`langgap`'s parser, from this checkout's source (not whichever copy is installed)."""
    if str(_SRC) not in sys.path[:1]:
        sys.path.insert(0, str(_SRC))
    from langgap.cli.main import build_parser as langgap_parser

    return langgap_parser()


def _escape(text: str) -> str:
    """Markdown-safe prose for a table cell; spans in backticks stay code."""
    parts = text.replace("\n", " ").split("`")
    for i in range(0, len(parts), 2):  # even parts are outside backticks
        for char in "\\*_[]<>":
            parts[i] = parts[i].replace(char, "\\" + char)
    return "`".join(parts).replace("|", "\\|")


def _code(text: str) -> str:
    return f"`{text}`"


def _subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction | None:
    return next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)


def _argument_row(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    formatter = parser._get_formatter()
    takes_value = action.nargs != 0
    if not action.option_strings:
        names = _code(formatter._get_default_metavar_for_positional(action))
    elif takes_value and (action.choices is None or action.metavar is not None):
        metavar = formatter._format_args(action, formatter._get_default_metavar_for_optional(action))
        names = ", ".join(_code(f"{o} {metavar}") for o in action.option_strings)
    else:  # a flag, or a choice listed below
        names = ", ".join(_code(o) for o in action.option_strings)
    details = []
    if action.required and action.option_strings:
        details.append("required")
    if action.choices is not None:
        details.append("one of " + ", ".join(_code(str(c)) for c in action.choices))
    shown_default = action.default not in (None, False, argparse.SUPPRESS, [], ())
    if action.option_strings and takes_value and shown_default and "default" not in (action.help or ""):
        details.append("default " + _code(str(action.default)))
    cell = _escape(formatter._expand_help(action)) if action.help else ""
    if details:
        cell = f"{cell} ({'; '.join(details)})" if cell else "; ".join(details)
    return f"| {names} | {cell} |"


def _section(parser: argparse.ArgumentParser, summary: str | None, depth: int) -> list[str]:
    lines = [f"{'#' * depth} `{parser.prog}`", ""]
    for text in (summary, parser.description):
        if text:
            lines += [_escape(text), ""]
    usage = parser.format_usage().removeprefix("usage: ").strip()
    lines += ["```text", usage, "```", ""]
    rows = [
        _argument_row(parser, a)
        for a in parser._actions
        if a.help != argparse.SUPPRESS and not isinstance(a, argparse._HelpAction | argparse._SubParsersAction)
    ]
    if rows:
        lines += ["| argument | meaning |", "|---|---|", *rows, ""]
    sub = _subparsers(parser)
    if sub is not None:
        helps = {choice.dest: choice.help for choice in sub._choices_actions}
        for name, child in sub.choices.items():
            lines += _section(child, helps.get(name), depth + 1)
    return lines


def reference_markdown(parser: argparse.ArgumentParser | None = None) -> str:
    """The CLI reference: one section per command, nested sub-commands one level deeper."""
    parser = parser or build_parser()
    sub = _subparsers(parser)
    helps = {choice.dest: choice.help for choice in sub._choices_actions}
    lines = []
    for name, child in sub.choices.items():
        lines += _section(child, helps.get(name), 2)
    return "\n".join(lines)


def on_page_markdown(markdown: str, page, config, files) -> str:
    """MkDocs event: fill the marker of the page that asks for the reference."""
    if MARKER not in markdown:
        return markdown
    return markdown.replace(MARKER, reference_markdown())
