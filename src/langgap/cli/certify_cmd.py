"""`langgap certify`: can any gripper pose that holds a drawer's handle be reached without collision?"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from dataclasses import asdict, replace
from pathlib import Path

from langgap.catalog.catalog import load_catalog, registry_path
from langgap.cli.tasks_cmd import add_catalog_option


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "certify",
        help="reachability of a drawer's handle: every gripper pose that holds it, solved and collision-checked",
    )
    parser.add_argument(
        "task", metavar="TASK", help="a task whose goal needs one drawer opened (alone, or with other sub-goals)"
    )
    add_catalog_option(parser)
    parser.add_argument("--init", type=int, default=0, help="the init state to analyse (default: %(default)s)")
    parser.add_argument("--out", metavar="FILE", help="write every pose's result as JSON")
    parser.add_argument(
        "--record",
        action="store_true",
        help="store the certificate with the gate verdict of the task and of every task needing the same drawer "
        "opened on the same source's scene (only when no pose is reachable and clear)",
    )
    parser.set_defaults(handler=run)


def run(args) -> int:
    from langgap.catalog.task import GateResult
    from langgap.catalog.verdicts import read_verdicts, record_verdicts
    from langgap.certify import TOLERANCE_M, handle_reach, sharing

    catalog = load_catalog(args.catalog)
    task = catalog.get(args.task)
    found = handle_reach(task, args.init)
    by_angle = defaultdict(list)
    for pose in found.reachable:
        by_angle[pose.angle_deg].append(pose)
    print(f"{'approach':>8}  {'reachable':>9}  {'clear':>5}  {'least hand intersection':<40}")
    for angle in sorted({p.angle_deg for p in found.poses}):
        poses = by_angle.get(angle, [])
        clear = [p for p in poses if p.clear]
        best = min(poses, key=lambda p: p.hand_penetration_m, default=None)
        least = "–" if best is None else f"{1000 * best.hand_penetration_m:.1f} mm {best.worst_contact}"
        print(f"{angle:>7}°  {len(poses):>9}  {len(clear):>5}  {least}")
    print(
        f"{task.id}: {len(found.poses)} poses, {len(found.reachable)} within the joint limits, "
        f"{len(found.clear)} clear of fixtures (tolerance {1000 * TOLERANCE_M:.0f} mm)"
    )
    if args.out:
        rows = [{k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in asdict(p).items()}
                for p in found.poses]  # fmt: skip
        Path(args.out).write_text(json.dumps({"task": task.id, "poses": rows}, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.out}")
    if not found.certified:
        print("not certified: a pose that holds the handle is reachable (the task is the oracle's to solve)")
        return 1
    print(f"certified infeasible: {found.certificate()}")
    if args.record:
        registry = registry_path(args.catalog)
        recorded = read_verdicts(registry)
        unvalidated = GateResult(0, 0, False, reason="certified infeasible")
        holders = [t.id for t in sharing(catalog, task)]
        certified = {i: replace(recorded.get(i) or unvalidated, certificate=found.certificate()) for i in holders}
        path = record_verdicts(registry, certified, None)
        print(f"recorded the certificate in {path} for {', '.join(holders)}")
    return 0
