"""`langgap validate`: the feasibility gate (scripted oracle on fixed init states, plus checks)."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

from langgap.catalog.verdicts import SAME_TRIAL
from langgap.cli.eval_cmd import add_stepping_option, print_switch_note
from langgap.cli.execution_flags import add_execution_options, add_share_rollouts_option, execution_options
from langgap.cli.tasks_cmd import add_catalog_option
from langgap.errors import LangGapError
from langgap.gate.rows import FULL_INITS
from langgap.gate.search import BUDGET
from langgap.vocabulary import FEASIBLE_RATE, SWITCH, SWITCH_RATE, TaskKind, Verdict

DEFAULT_POLICY = "oracle"


def add_gate_options(parser) -> None:
    """Options shared by `validate` and `generate --gate-inits`: the execution flags, and the gate's own."""
    add_execution_options(parser)
    parser.add_argument("--run", metavar="DIR", help="keep the oracle's episodes in this run directory (resumable)")
    parser.add_argument("--resume", action="store_true", help="continue an interrupted validation in --run")
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
        # argparse %-formats help strings: the percent sign is doubled.
        "validate",
        help=f"prove tasks doable: the scripted oracle must reach {FEASIBLE_RATE:.0%}% on their init states",
    )
    parser.add_argument("tasks", nargs="?", default="all", metavar="SELECTION", help="task selection (default: all)")
    add_catalog_option(parser)
    parser.add_argument("--inits", type=int, default=FULL_INITS, help="first K init states per task (default: all 50)")
    parser.add_argument("--policy", help=f"the scripted policy that proves tasks (default: {DEFAULT_POLICY})")
    parser.add_argument(
        "--blind",
        action="store_true",
        help=f"also run `blind` on the same episodes and check its claims ({TaskKind.ORIGINAL}s as the oracle, 0 %% "
        "elsewhere)",
    )
    parser.add_argument(
        "--claims-only",
        action="store_true",
        help="only the claims about starts (one t0 state per scene and init state, no scene goal at t0): "
        "every task's own environment reset to each init state (with --stepping, on the execution flags' "
        "workers), no policy run",
    )
    parser.add_argument(
        "--condition",
        action="append",
        metavar=f"{SWITCH}K",
        help="the switch gate instead (repeatable): per task and K, the oracle must follow an instruction switched "
        f"at policy step K on {SWITCH_RATE:.0%}% of the init states, else the task is {Verdict.UNPROVEN} at that K; "
        "--record keeps the verdicts in <registry>.switch-gate.json",
    )
    add_share_rollouts_option(parser)
    parser.add_argument("--out", metavar="FILE", help="write the report as JSON (a row per task, the claims)")
    parser.add_argument(
        "--record",
        action="store_true",
        help="record the verdicts beside the catalog's registry (rejected tasks leave the default selection)",
    )
    add_gate_options(parser)
    parser.set_defaults(handler=run, smoke=("tasks", "inits", "workers"))


def run_gate(
    args,
    catalog: str,
    selection: str,
    inits: int,
    policy: str = DEFAULT_POLICY,
    blind: bool = False,
    recording: bool = False,
    share_rollouts: bool = False,
    record: bool = False,
):
    """Run the feasibility gate with the options of `add_gate_options`; returns its `Validation`. Searched
    demonstrations go beside the catalog's registry when `recording` or `record` (which records the verdicts);
    `share_rollouts`: an instruction-blind policy's episodes (`blind`'s) share rollouts."""
    from langgap.gate import validate
    from langgap.gate.recording import demonstrations_dir

    return validate(
        catalog,
        selection,
        inits=inits,
        options=execution_options(args, share_rollouts=share_rollouts),
        run=args.run,
        resume=args.resume,
        policy=policy,
        blind=blind,
        stepping=args.stepping,
        search_budget=args.search_budget,
        demonstrations=demonstrations_dir(catalog) if recording else None,
        record=record,
    )


def run(args) -> int:
    from langgap.gate.text import table_text

    if args.claims_only:
        return _claims_only(args)
    if args.condition:
        return _switch_gate(args)
    found = run_gate(
        args,
        args.catalog,
        args.tasks,
        args.inits,
        args.policy or DEFAULT_POLICY,
        blind=args.blind,
        share_rollouts=args.share_rollouts,
        record=args.record,
    )
    if found.inherited:
        print(
            f"{len(found.inherited)} selected task(s) take the verdict of a task with {SAME_TRIAL} "
            f"(langgap tasks show ID names it): not run"
        )
    if not found.rows:
        return 0
    print(table_text(found.rows))
    _print_claims(found, args.out)
    if found.recorded is not None:
        for row in found.rows:
            if not row.feasible:
                print(f"{row.id}: {row.verdict(args.inits, proof=found.proofs.get(row.id, '')).evidence}")
        print(f"recorded verdicts in {found.recorded}")
    return 0 if found.passed else 1


def _switch_gate(args) -> int:
    """The switch gate (`langgap.gate.switch`): the oracle under each `switch:K`; its flags that vary or add to
    the plain gate's episodes are refused."""
    from langgap.catalog.catalog import load_catalog
    from langgap.gate.switch import record_switch, switch_conditions, switch_table_text, validate_switch
    from langgap.gate.validation import check_resume

    plain_only = {
        "--blind": args.blind,
        "--search-budget": args.search_budget is not None,
        "--share-rollouts": args.share_rollouts,
    }
    given = [flag for flag, present in plain_only.items() if present]
    if given:
        raise LangGapError(f"--condition runs the switch gate, which has no {' or '.join(given)}")
    check_resume(args.resume, args.run)
    policy = args.policy or DEFAULT_POLICY
    conditions = switch_conditions(args.condition)
    print_switch_note(args.catalog, [t.id for t in load_catalog(args.catalog).select(args.tasks)], conditions)
    rows = validate_switch(
        args.catalog,
        args.tasks,
        conditions,
        inits=args.inits,
        options=execution_options(args),
        run=args.run,
        resume=args.resume,
        policy=policy,
        stepping=args.stepping,
    )
    print(switch_table_text(rows))
    if args.out:
        data = [{**asdict(r), "feasible": r.feasible, "reason": r.reason} for r in rows]
        Path(args.out).write_text(json.dumps({"switch": data}, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.out}")
    if args.record:
        path = record_switch(args.catalog, rows, inits=args.inits, policy=policy, stepping=args.stepping)
        print(f"recorded switch verdicts in {path}")
    return 0 if all(r.feasible for r in rows) else 1


def _claims_only(args) -> int:
    """The claims about starts alone; the flags of a gate that runs a policy are refused."""
    from langgap.catalog.catalog import load_catalog
    from langgap.gate import Validation
    from langgap.gate.claims import start_claims
    from langgap.gate.probes import scene_starts

    policy_flags = {
        "--policy": args.policy is not None,
        "--blind": args.blind,
        "--record": args.record,
        "--run": args.run is not None,
        "--resume": args.resume,
        "--search-budget": args.search_budget is not None,
        "--condition": bool(args.condition),
        "--share-rollouts": args.share_rollouts,
    }
    given = [flag for flag, present in policy_flags.items() if present]
    if given:
        raise LangGapError(
            f"--claims-only runs no policy: it stores no episodes, records no verdicts and searches nothing "
            f"(drop {', '.join(given)})"
        )
    tasks = load_catalog(args.catalog).select(args.tasks)
    starts = scene_starts(args.catalog, tasks, args.inits, execution_options(args), stepping=args.stepping)
    found = Validation([], start_claims(starts))
    _print_claims(found, args.out)
    return 0 if found.passed else 1


def _print_claims(found, out: str | None) -> None:
    """Print the claims; with `out`, write the whole validation there as JSON."""
    from langgap.gate.text import claims_text, report

    print(claims_text(found.claims))
    if out:
        Path(out).write_text(json.dumps(report(found), indent=1) + "\n", encoding="utf-8")
        print(f"wrote {out}")
