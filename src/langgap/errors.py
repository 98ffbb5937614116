"""Exception types. Every user-facing failure is a `LangGapError` whose message is one line."""


class LangGapError(Exception):
    """Base class: the CLI prints `error: <message>` and exits with `exit_code`."""

    exit_code = 2


class CatalogError(LangGapError):
    """The task registry or a task selection is invalid."""


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
