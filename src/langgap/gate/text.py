"""The gate as text: the printed table, the summary by rejection reason, the claims, and the JSON report."""

from __future__ import annotations

from collections import Counter
from dataclasses import asdict

from langgap.catalog.verdicts import verdict_counts
from langgap.gate.claims import Claim
from langgap.gate.rows import TaskValidation
from langgap.gate.validation import Validation
from langgap.vocabulary import CEILING_TARGET, Verdict


def claims_text(claims: list[Claim]) -> str:
    """One line per claim (and its first violations)."""
    lines = []
    for claim in claims:
        verdict = "holds" if claim.holds else "FAILS (release blocker)"
        lines.append(f"claim: {claim.name}: {verdict} ({claim.checked} checked)")
        lines += [f"  {v}" for v in claim.violations]
    return "\n".join(lines)


def report(found: Validation) -> dict:
    """The validation as JSON data: a row per task, and the claims."""
    return {"tasks": [asdict(r) for r in found.rows], "claims": [asdict(c) for c in found.claims]}


def table_text(rows: list[TaskValidation]) -> str:
    """A printed table: one line per task, then the totals."""
    width = max((len(r.id) for r in rows), default=4)
    lines = [f"{'task':<{width}}  {'oracle':>9}  {'rate':>6}  {'steps':>11}  verdict"]
    for r in rows:
        verdict = r.word if r.feasible else f"{r.word} ({r.reason})"
        if r.feasible and r.rate < CEILING_TARGET:
            verdict += f", the oracle below the {CEILING_TARGET:.0%} ceiling target"
        if r.demonstrated_inits:
            verdict += f"; searched demonstrations on init state(s) {', '.join(map(str, r.demonstrated_inits))}"
        lines.append(
            f"{r.id:<{width}}  {r.successes:>4}/{r.episodes:<4}  {100 * r.rate:>5.1f}%  "
            f"{r.mean_steps:>5.0f}/{r.max_steps:<5}  {verdict}"
        )
    episodes = sum(r.episodes for r in rows)
    successes = sum(r.successes for r in rows)
    below = [r.id for r in rows if r.rate < CEILING_TARGET]
    lines.append(
        f"{len(rows)} tasks, {successes}/{episodes} oracle successes "
        f"({100 * successes / max(1, episodes):.1f}%); {verdict_counts(r.word for r in rows)}; "
        f"the oracle below {CEILING_TARGET:.0%} on {len(below)}"
    )
    return "\n".join(lines)


def gate_summary(rows: list[TaskValidation]) -> str:
    """The verdicts counted, the rejected ones grouped by verdict and the checks they failed."""
    lines = [f"gate: {verdict_counts(r.word for r in rows)}"]
    for (word, reason), count in Counter(
        (r.word, r.reason.split(";")[0].split(" ")[0] if r.reason.startswith("oracle") else r.reason)
        for r in rows
        if not r.feasible
    ).most_common():
        lines.append(f"  {word:<{max(map(len, Verdict))}} {count:>4}: {reason}")
    return "\n".join(lines)
