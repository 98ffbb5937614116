"""A check's verdict and how it is shown: `langgap doctor` and `langgap check-policy` print the same lines."""

from __future__ import annotations

from dataclasses import dataclass

_NAME_WIDTH = 15
_INDENT = " " * (len("[FAIL] ") + _NAME_WIDTH + 1)


@dataclass
class Check:
    """One verdict: `ok` True (passed), False (failed: `remedy` says how to fix it) or None (not run). A check
    that passed with a `warning` passed, but found something that costs the run (time, a wasted render)."""

    name: str
    ok: bool | None
    detail: str
    remedy: str = ""
    warning: str = ""


def check_lines(check: Check) -> list[str]:
    """`check` as printed: `[ok  ]`, `[warn]`, `[FAIL]` or `[skip]`, its name and detail (a detail's further
    lines indented under its first), and a failure's fix or a warning."""
    verdict = {True: "warn" if check.warning else "ok  ", False: "FAIL", None: "skip"}[check.ok]
    first, *more = check.detail.splitlines() or [""]
    lines = [f"[{verdict}] {check.name:<{_NAME_WIDTH}} {first}", *(_INDENT + line for line in more)]
    if check.ok is False and check.remedy:
        lines.append(f"{_INDENT}fix: {check.remedy}")
    if check.ok and check.warning:
        lines.append(f"{_INDENT}warning: {check.warning}")
    return lines
