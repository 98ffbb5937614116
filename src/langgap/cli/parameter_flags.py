"""A parameter as the command line spells it. A `ParameterError` names each parameter as a Python caller
passes it (`episodes`, `max_attempts`); the CLI user reads the flag that sets it (`--episodes`,
`--max-attempts`, or `collect`'s `--max-task-attempts`), found in the parser's own actions."""

from __future__ import annotations

import argparse
from collections.abc import Iterator

from langgap.errors import LangGapError, ParameterError, PolicyArgumentError

# The parameters set by a flag of another `dest`; every other parameter is its flag's dest. The retries' flag
# stores `work_attempts`: `collect` spells it `--max-task-attempts`, its own `--max-attempts` being another option.
DESTS = {"timeout_s": "timeout", "max_attempts": "work_attempts", "conditions": "condition"}
# A parameter that commands set under another name: the init states each task runs are `eval --episodes` and
# `validate --inits` (which reaches `RunSpec.create` as `episodes`).
SYNONYMS = {"episodes": ("inits",)}


def _parsers(parser: argparse.ArgumentParser, args: argparse.Namespace) -> Iterator[argparse.ArgumentParser]:
    """`parser` and the sub-command parsers that read `args`, outermost first."""
    yield parser
    for action in parser._actions:  # argparse lists actions only in this private field
        if isinstance(action, argparse._SubParsersAction) and getattr(args, action.dest, None) in action.choices:
            yield from _parsers(action.choices[getattr(args, action.dest)], args)


def _flag(action: argparse.Action) -> str:
    return next((o for o in action.option_strings if o.startswith("--")), action.option_strings[0])


def error_message(error: LangGapError, parser: argparse.ArgumentParser, args: argparse.Namespace) -> str:
    """The line the CLI prints for `error`, a `ParameterError`'s parameters spelled as the flags of the command
    that parsed `args`: the flag that sets the parameter (`SYNONYMS`: `validate --inits` sets `episodes`), else
    the flag of its name, as the other commands spell it; a policy's argument as `--policy-arg NAME`."""
    if not isinstance(error, ParameterError):
        return str(error)
    if isinstance(error, PolicyArgumentError):
        return error.naming({p: f"--policy-arg {p}" for p in error.parameters})
    flags = {a.dest: _flag(a) for p in _parsers(parser, args) for a in p._actions if a.option_strings}

    def spelled(parameter: str) -> str:
        dest = DESTS.get(parameter, parameter)
        setting = next((flags[d] for d in (dest, *SYNONYMS.get(parameter, ())) if d in flags), None)
        return setting or "--" + dest.replace("_", "-")

    return error.naming({p: spelled(p) for p in error.parameters})
