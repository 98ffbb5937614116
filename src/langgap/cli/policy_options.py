"""The options that name a policy (`--policy-arg k=v`, repeatable) as the commands that build one share them, and
the `langgap check-policy` command line that checks a run's policy."""

from __future__ import annotations

import shlex

from langgap.catalog.catalog import DEFAULT_CATALOG
from langgap.errors import LangGapError


def add_policy_arg_option(parser) -> None:
    """`--policy-arg K=V`, repeatable."""
    parser.add_argument("--policy-arg", action="append", metavar="K=V", help="policy argument (repeatable)")


def parse_key_values(pairs: list[str] | None, option: str) -> dict[str, str]:
    """`k=v` strings to a dict; a malformed pair is a one-line error."""
    out: dict[str, str] = {}
    for pair in pairs or []:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise LangGapError(f"{option} expects key=value, got {pair!r}")
        out[key] = value
    return out


def check_policy_command(policy: str, policy_args: dict[str, str], catalog: str, tasks: str | None) -> str:
    """The `langgap check-policy` command that checks `policy` for a run of `tasks` on `catalog`."""
    words = ["langgap", "check-policy", policy]
    for key, value in policy_args.items():
        words += ["--policy-arg", f"{key}={value}"]
    if catalog != DEFAULT_CATALOG:
        words += ["--catalog", catalog]
    if tasks is not None:
        words += ["--tasks", tasks]
    return shlex.join(words)
