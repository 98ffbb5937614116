"""Exception types. Every user-facing failure is a `LangGapError` whose message is one line."""

from __future__ import annotations

import functools
import string
from collections.abc import Mapping


class LangGapError(Exception):
    """Base class: the CLI prints `error: <message>` and exits with `exit_code`.

    Attributes:
        exit_code: The CLI's exit code for the error (2: bad input; 4: the work failed).
    """

    exit_code = 2


class ParameterError(LangGapError):
    """An argument is out of range or needs another one, or the way on is another argument (`pass resume to
    continue it`). The message names each parameter as a Python caller passed it (`episodes must be at least 1,
    got 0`); a front end that spells them otherwise reads `naming` (the CLI: `--episodes must be at least 1, got
    0`). Below the CLI every error that names a parameter is one: only the CLI spells flags.

    Args:
        template: The message, each parameter written as a `{name}` field.
        **values: The template's other fields: what the caller gave, formatted by the template and never
            read as fields themselves.

    Attributes:
        parameters: The parameters the message names, in its order.
        template: The message as given, with its fields.
        values: The values given for the fields that are not parameters.
    """

    def __init__(self, template: str, **values: object) -> None:
        fields = (field for _, field, _, _ in string.Formatter().parse(template) if field)
        self.template = template
        self.values = values
        self.parameters = tuple(dict.fromkeys(f for f in fields if f not in values))
        super().__init__(self.naming({}))

    def naming(self, names: Mapping[str, str]) -> str:
        """The message with each parameter spelled as `names` spells it.

        Args:
            names: Parameter -> its spelling (`{"episodes": "--episodes"}`); one it lacks reads as passed.

        Returns:
            The message.
        """
        return self.template.format_map({**{p: names.get(p, p) for p in self.parameters}, **self.values})

    def __reduce__(self) -> tuple:
        # Copied and pickled as its template and values: its message (`args`) is no template.
        return functools.partial(type(self), **self.values), (self.template,)


class CatalogError(LangGapError):
    """The task registry or a task selection is invalid."""


class CatalogParameterError(CatalogError, ParameterError):
    """An argument that selects or splits a catalog's tasks is invalid, named as the caller passed it."""


class PolicyArgumentError(ParameterError):
    """A policy's argument is missing or refused. Its parameters are the arguments of the policy's constructor
    (`make_policy`'s `args`), which the CLI spells as `--policy-arg NAME` (`{checkpoint}=PATH` reads
    `--policy-arg checkpoint=PATH` there)."""


class UnknownTaskError(CatalogError):
    """A task id (or selection term) matches no task."""


class BddlError(LangGapError):
    """A BDDL file is malformed or names things that are not in its scene."""


class SimulationError(LangGapError):
    """The simulator could not build, reset or step an environment."""


class InitStateError(SimulationError):
    """An init-state index is out of range, or an init state did not apply."""


class DependencyNotInstalled(LangGapError):
    """An optional dependency is missing; the message says how to install it."""


class PolicyServerError(LangGapError):
    """A remote policy server is unreachable, timed out, failed, or sent a malformed reply."""


def one_line(exc: BaseException) -> str:
    """`Type: last line of the message`: the same line for the same cause (the scheduler's fail-fast compares them)."""
    lines = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {lines[-1]}" if lines else type(exc).__name__
