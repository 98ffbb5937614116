"""Mutation testing of the core every result rests on, against the fast unit layer (tests/unit).

mutmut (configured in pyproject.toml, `[tool.mutmut]`) copies the project to `mutants/`, makes many small
changes (mutants) to the modules below, one at a time, and runs the unit tests that reach the changed function.
A mutant the tests fail on is killed; one they pass is a survivor: a change to the code no test notices.
Each survivor is either killed by a new test or reviewed in bench/mutation_survivors.toml (why it is equivalent
or not worth a test); this script prints, per module, the score and every survivor nobody has reviewed yet (and
the reviews that no longer match a survivor).

    .venv/bin/python bench/bench_mutation.py                  # every module below
    .venv/bin/python bench/bench_mutation.py --module store   # one (repeat --module for more)

It exits 1 while a survivor is unreviewed, 2 when mutmut cannot run (the unit layer fails unmutated).
Each run starts from a fresh `mutants/` (so it sees the current tests); mutation runs are not part of CI.
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import os
import shutil
import subprocess
import sys
import time
import tomllib
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SURVIVORS = ROOT / "bench" / "mutation_survivors.toml"
WORK = ROOT / "mutants"


@dataclass(frozen=True)
class Module:
    """A mutated module: its file, and the mutants of it that count (mutmut's names, as globs)."""

    path: str
    mutants: tuple[str, ...] = ()

    @property
    def dotted(self) -> str:
        return self.path.removeprefix("src/").removesuffix(".py").replace("/", ".")

    @property
    def globs(self) -> tuple[str, ...]:
        return tuple(f"{self.dotted}.{m}" for m in self.mutants) or (f"{self.dotted}.*",)


# Smallest first. catalog.py counts only `Catalog.select` and the term matching it rests on.
MODULES = {
    "text": Module("src/langgap/policies/text.py"),
    "runner_sentences": Module("src/langgap/catalog/runner_sentences.py"),
    "vocabulary": Module("src/langgap/vocabulary.py"),
    "gate_rows": Module("src/langgap/gate/rows.py"),
    "sentences": Module("src/langgap/audit/sentences.py"),
    "stats": Module("src/langgap/report/stats.py"),
    "store": Module("src/langgap/store.py"),
    "plan": Module("src/langgap/engine/plan.py"),
    "records": Module("src/langgap/records.py"),
    "spec": Module("src/langgap/engine/spec.py"),
    "goals": Module("src/langgap/goals.py"),
    "select": Module(
        "src/langgap/catalog/catalog.py",
        ("xǁCatalogǁselect__mutmut_*", "xǁCatalogǁ_match_term__mutmut_*", "xǁCatalogǁ_no_match__mutmut_*"),
    ),
    "audit": Module("src/langgap/audit/findings.py"),
}

# mutmut's exit codes per mutant (mutmut.stats.status_by_exit_code), folded into what the score counts.
_KILLED, _TIMEOUT, _SURVIVED, _NO_TESTS = {1, 3}, {24, -24, 36, 152, 255}, {0}, {5, 33}


def status(code: int | None) -> str:
    """What a mutant's exit code means: killed, timeout, survived, no tests, or not run."""
    if code in _KILLED:
        return "killed"
    if code in _TIMEOUT:
        return "timeout"
    if code in _SURVIVED:
        return "survived"
    if code in _NO_TESTS:
        return "no tests"
    return "not run" if code is None else f"exit {code}"


def changed_lines(diff: str) -> tuple[str, str]:
    """A mutant's diff as the lines it removes and adds (stripped): what a review names, since mutmut's
    numbers change whenever the function does."""
    body = [line for line in diff.splitlines() if not line.startswith(("---", "+++", "@@"))]
    removed = "\n".join(line[1:].strip() for line in body if line.startswith("-"))
    added = "\n".join(line[1:].strip() for line in body if line.startswith("+"))
    return removed, added


def function_of(mutant: str) -> str:
    """The function a mutant changes (`xǁRunStoreǁappend`, `x_wilson_interval`)."""
    return mutant.rsplit(".", 1)[1].rsplit("__mutmut_", 1)[0]


def reviewed(path: Path = SURVIVORS) -> list[dict]:
    """The reviewed survivors: module, function, removed, added, reason (bench/mutation_survivors.toml)."""
    return tomllib.loads(path.read_text(encoding="utf-8")).get("survivor", []) if path.exists() else []


def review_of(module: str, mutant: str, diff: str, reviews: list[dict]) -> dict | None:
    """The review that names this mutant (same module, function and changed lines), if any."""
    removed, added = changed_lines(diff)
    for review in reviews:
        if (review["module"], review["function"]) == (module, function_of(mutant)) and (
            review["removed"].strip(),
            review["added"].strip(),
        ) == (removed, added):
            return review
    return None


def run_mutmut(modules: dict[str, Module], jobs: int) -> None:
    """Run mutmut afresh over the modules' mutants (mutants/ is rebuilt, so new and changed tests count)."""
    shutil.rmtree(WORK, ignore_errors=True)
    globs = [g for m in modules.values() for g in m.globs]
    command = [sys.executable, "-m", "mutmut", "run", "--max-children", str(jobs), *globs]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        tail = (done.stdout + done.stderr).strip().splitlines()[-25:]
        print("\n".join(tail), file=sys.stderr)
        print(f"error: mutmut could not run (exit {done.returncode}); the lines above say why", file=sys.stderr)
        sys.exit(2)


def results(module: Module) -> dict[str, str]:
    """Each counted mutant of the module and its status, from mutmut's record in mutants/."""
    meta = json.loads((WORK / f"{module.path}.meta").read_text(encoding="utf-8"))
    return {
        name: status(code)
        for name, code in meta["exit_code_by_key"].items()
        if any(fnmatch.fnmatchcase(name, g) for g in module.globs)
    }


def diff_of(mutant: str, module: Module) -> str:
    """The mutant's unified diff against the original function."""
    from mutmut.mutation.diff_apply import get_diff_for_mutant  # mutmut reads its config from the cwd

    return get_diff_for_mutant(mutant, path=Path(module.path))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--module", action="append", choices=sorted(MODULES), help="mutate only this module")
    parser.add_argument("--jobs", type=int, default=2, help="mutants tested at once (default 2)")
    args = parser.parse_args(argv)
    modules = {name: MODULES[name] for name in args.module} if args.module else MODULES
    os.chdir(ROOT)

    start = time.monotonic()
    run_mutmut(modules, args.jobs)
    elapsed = time.monotonic() - start

    reviews = reviewed()
    unreviewed: list[str] = []
    matched: list[int] = []
    print(f"{'module':<18} {'killed/total':>13} {'score':>6} {'timeout':>7} {'survived':>8} {'no tests':>8} reviewed")
    for name, module in modules.items():
        found = results(module)
        counts = Counter(found.values())
        total = len(found)
        survivors = sorted(m for m, s in found.items() if s in ("survived", "no tests"))
        notes = {m: review_of(name, m, diff_of(m, module), reviews) for m in survivors}
        score = (counts["killed"] + counts["timeout"]) / total if total else 1.0
        print(
            f"{name:<18} {counts['killed']:>6}/{total:<6} {score:>6.1%} {counts['timeout']:>7} "
            f"{counts['survived']:>8} {counts['no tests']:>8} {sum(n is not None for n in notes.values())}"
        )
        others = {s: n for s, n in counts.items() if s not in ("killed", "timeout", "survived", "no tests")}
        if others:
            print(f"{'':<18} also: {others}")
        unreviewed += [f"{name}: {m} ({found[m]})\n{diff_of(m, module)}" for m, note in notes.items() if note is None]
        matched += [id(note) for note in notes.values() if note is not None]
    print(f"total time {elapsed:.0f} s")
    stale = [r for r in reviews if r["module"] in modules and id(r) not in matched]
    for review in stale:
        print(
            f"note: a review matches no survivor now (killed, or its code changed): {review['module']} "
            f"{review['function']}: {review['removed']!r} -> {review['added']!r}"
        )
    if unreviewed:
        print(f"\n{len(unreviewed)} survivors not reviewed in {SURVIVORS.relative_to(ROOT)}:\n")
        print("\n\n".join(unreviewed))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
