"""`langgap validate`: the feasibility gate (scripted oracle on fixed init states, plus checks)."""

from __future__ import annotations

import json
from pathlib import Path

from langgap.catalog.task import INFEASIBLE, unproven
from langgap.cli.eval_cmd import add_stepping_option
from langgap.cli.tasks_cmd import add_catalog_option
from langgap.errors import LangGapError
from langgap.search import BUDGET
from langgap.validate import FEASIBLE_RATE, FULL_INITS


def add_gate_options(parser) -> None:
    """Options shared by `validate` and `generate --gate-inits`."""
    parser.add_argument("--workers", type=int, default=1, help="local worker processes (default: %(default)s)")
    parser.add_argument("--run", metavar="DIR", help="keep the oracle's episodes in this run directory (resumable)")
    parser.add_argument("--resume", action="store_true", help="continue an interrupted validation in --run")
    parser.add_argument("--no-progress", action="store_true")
    parser.add_argument(
        "--search-budget",
        type=int,
        metavar="N",
        help="candidate episodes searched for a demonstration on each init state the oracle fails; those "
        f"found are stored, replayed and counted (0: no search; default: {BUDGET} for the oracle's gate)",
    )
    add_stepping_option(parser)


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "validate", help=f"prove tasks doable: the scripted oracle must reach {FEASIBLE_RATE:.0%} on their init states"
    )
    parser.add_argument("tasks", nargs="?", default="all", metavar="SELECTION", help="task selection (default: all)")
    add_catalog_option(parser)
    parser.add_argument("--inits", type=int, default=FULL_INITS, help="first K init states per task (default: all 50)")
    parser.add_argument(
        "--policy", default="oracle", help="the scripted policy that proves tasks (default: %(default)s)"
    )
    parser.add_argument(
        "--blind",
        action="store_true",
        help="also run `blind` on the same episodes and check its claims (originals as the oracle, 0 %% elsewhere)",
    )
    parser.add_argument(
        "--claims-only",
        action="store_true",
        help="only the claims about starts (one t0 state per scene and init state, no scene goal at t0): "
        "every task's own environment reset to each init state, no policy run",
    )
    parser.add_argument("--out", metavar="FILE", help="write the report as JSON (a row per task, the claims)")
    parser.add_argument(
        "--record",
        action="store_true",
        help="record the verdicts beside the catalog's registry (rejected tasks leave the default selection)",
    )
    add_gate_options(parser)
    parser.set_defaults(handler=run)


def run_gate(
    args, catalog: str, selection: str, inits: int, policy: str = "oracle", blind: bool = False, recording: bool = False
):
    """Run the feasibility gate with the options of `add_gate_options`; returns its `Validation`. Searched
    demonstrations go beside the catalog's registry when `recording` (the verdicts will name them)."""
    budget = args.search_budget
    if budget is not None and budget < 0:
        raise LangGapError(f"--search-budget must be >= 0, got {budget}")
    if budget and policy != "oracle":
        raise LangGapError(f"--search-budget varies the oracle's plan; --policy {policy} has none to vary")
    if budget is None:
        budget = BUDGET if policy == "oracle" else 0
    from langgap.validate import demonstrations_dir, validate

    return validate(
        catalog,
        selection,
        inits=inits,
        workers=args.workers,
        run=args.run,
        resume=args.resume,
        policy=policy,
        progress=not args.no_progress,
        blind=blind,
        stepping=args.stepping,
        search_budget=budget,
        demonstrations=demonstrations_dir(catalog) if recording else None,
    )


def run(args) -> int:
    from langgap.validate import prove_rejected, record, table_text

    if args.claims_only:
        return _claims_only(args)
    found = run_gate(args, args.catalog, args.tasks, args.inits, args.policy, blind=args.blind, recording=args.record)
    print(table_text(found.rows))
    _print_claims(found, args.out)
    if args.record:
        proofs = prove_rejected(args.catalog, found.rows, args.inits)
        for row in found.rows:
            if row.id in proofs:
                print(f"{row.id}: {INFEASIBLE}: {proofs[row.id]}")
            elif row.short:
                print(f"{row.id}: {unproven(row.successes, row.episodes)}")
        options = dict(inits=args.inits, policy=args.policy, stepping=args.stepping, proofs=proofs)
        path = record(args.catalog, found.rows, **options)
        print(f"recorded verdicts in {path}")
    return 0 if found.passed else 1


def _claims_only(args) -> int:
    from langgap.catalog.catalog import load_catalog
    from langgap.validate import Validation, scene_starts, start_claims

    if args.record or args.blind:
        raise LangGapError("--claims-only runs no policy: it records no verdicts and runs no blind policy")
    catalog = load_catalog(args.catalog)
    found = Validation([], start_claims(scene_starts(catalog, catalog.select(args.tasks), args.inits)))
    _print_claims(found, args.out)
    return 0 if found.passed else 1


def _print_claims(found, out: str | None) -> None:
    """Print the claims; with `out`, write the whole validation there as JSON."""
    from langgap.validate import claims_text, report

    print(claims_text(found.claims))
    if out:
        Path(out).write_text(json.dumps(report(found), indent=1) + "\n", encoding="utf-8")
        print(f"wrote {out}")
