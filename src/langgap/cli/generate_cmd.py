"""`langgap generate`: enumerate same-scene tasks into a generated registry (`full`, or `langgap-beyond` with
`--catalog`) and print its counts; or read another benchmark's tasks from its package (`--catalog libero-pro`,
`libero-plus-language`), run LangGap's file checks on them and record the findings."""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable

from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
from langgap.catalog.task import DIMENSIONS, Task
from langgap.cli.validate_cmd import add_gate_options, run_gate
from langgap.errors import LangGapError
from langgap.generation.external import EXTERNAL
from langgap.generation.generate import (
    BEYOND_CATALOG,
    FULL_CATALOG,
    GENERATED,
    default_registry_path,
    generate_tasks,
    write_registry,
)
from langgap.stack import SUITES
from langgap.vocabulary import TaskKind


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "generate", help="enumerate every candidate same-scene task of LIBERO's scenes into a registry"
    )
    parser.add_argument(
        "--catalog",
        choices=[*GENERATED, *EXTERNAL],
        default=FULL_CATALOG,
        help="which catalog to generate: the full task space (default), the dimensions beyond the paper's, or "
        "LIBERO-PRO's / LIBERO-Plus's language perturbations read from their packages",
    )
    parser.add_argument(
        "--out", metavar="FILE", help="registry file to write (default: the package's catalog/registry/CATALOG.yaml)"
    )
    parser.add_argument(
        "--suites",
        nargs="+",
        metavar="SUITE",
        default=list(SUITES),
        help="suites to enumerate, e.g. libero_goal or goal (default: all four)",
    )
    parser.add_argument(
        "--gate-inits",
        type=int,
        default=0,
        metavar="K",
        help="run the feasibility gate (oracle on the first K init states) on every task and record it",
    )
    first_gate_option = len(parser._actions)  # argparse lists actions only in this private field
    add_gate_options(parser)
    # The gate's options act only through --gate-inits: `run` refuses any of them set without it.
    gate_options = {a.dest: (a.option_strings[0], a.default) for a in parser._actions[first_gate_option:]}
    parser.set_defaults(handler=run, gate_options=gate_options, smoke=("gate_inits", "workers"))


def summary_lines(tasks: list[Task]) -> list[str]:
    """Counts per scene, suite and dimension, the paper's tasks found, and the gate's verdicts if it ran."""
    scenes = _counts(tasks, lambda t: t.source)
    suites = _counts(tasks, lambda t: t.suite)
    width = max(len(s) for s in scenes)
    present = {t.dimension for t in tasks}
    columns = [d for d in DIMENSIONS if d in present]
    total = Counter(t.dimension for t in tasks)
    lines = [f"{'scene (source task)':<{width}}  " + "  ".join(columns)]
    for name, counts in [*scenes.items(), *suites.items(), ("total", total)]:
        lines.append(f"{name:<{width}}  " + "  ".join(f"{counts[c]:>{len(c)}}" for c in columns))
    originals = total[TaskKind.ORIGINAL]
    lines.append(f"{len(tasks)} tasks: {originals} {TaskKind.ORIGINAL}, {len(tasks) - originals} {TaskKind.EXTENDED}")

    if not any(t.in_langgap99 and t.kind == TaskKind.EXTENDED for t in tasks):
        return lines  # a catalog built on the originals only (langgap-beyond)
    paper = [t for t in load_catalog(DEFAULT_CATALOG) if t.suite in suites]
    found = {t.id for t in tasks if t.in_langgap99}
    missing = [t.id for t in paper if t.id not in found]
    lines.append(
        f"langgap99: {len(paper) - len(missing)}/{len(paper)} of the paper's tasks in these suites found"
        + (f"; missing: {', '.join(missing)}" if missing else "")
    )

    return lines


def _counts(tasks: list[Task], key: Callable[[Task], str]) -> dict[str, Counter]:
    """Tasks per dimension, for each value of `key`, in order of first appearance."""
    counts: dict[str, Counter] = {}
    for task in tasks:
        counts.setdefault(key(task), Counter())[task.dimension] += 1
    return counts


def _check_gate_options(args) -> None:
    """Refuse gate options that would change nothing: a negative `--gate-inits`, any gate option without
    `--gate-inits`, `--resume` without the `--run` it continues."""
    if args.gate_inits < 0:
        raise LangGapError(f"--gate-inits must be at least 0, got {args.gate_inits}")
    if not args.gate_inits:
        given = [flag for dest, (flag, default) in args.gate_options.items() if getattr(args, dest) != default]
        if given:
            raise LangGapError(f"{', '.join(given)} only apply to the feasibility gate (--gate-inits K)")
    if args.resume and not args.run:
        raise LangGapError("--resume continues the gate's episodes kept in --run: give --run DIR")


def run(args) -> int:
    _check_gate_options(args)
    if args.catalog in EXTERNAL:
        return _run_external(args)
    if args.catalog == BEYOND_CATALOG:
        from langgap.generation.beyond import generate_beyond

        tasks = generate_beyond(args.suites)
    else:
        tasks = generate_tasks(args.suites)
    path = write_registry(tasks, args.out or default_registry_path(args.catalog), args.catalog)
    print("\n".join(summary_lines(tasks)))
    print(f"wrote {path}")
    if args.gate_inits:
        from langgap.gate.recording import record
        from langgap.gate.text import gate_summary

        rows = run_gate(args, str(path), "all", args.gate_inits, recording=True).rows
        print(gate_summary(rows))
        print(f"recorded verdicts in {record(str(path), rows, inits=args.gate_inits, stepping=args.stepping)}")
    return 0


def _run_external(args) -> int:
    """Read the catalog from its package, write it, run the file checks and record their findings beside it."""
    from langgap.audit.findings import audit_text, duplicate_counts_text, record_audit
    from langgap.audit.run import files_about, files_findings
    from langgap.catalog.catalog import load_catalog_file
    from langgap.generation.external import GENERATORS, write_external

    if args.gate_inits or args.suites != list(SUITES):
        raise LangGapError(
            f"--gate-inits and --suites do not apply to {args.catalog}: it is read whole from its package"
        )
    generated = GENERATORS[args.catalog]()
    path = write_external(generated, args.out or default_registry_path(args.catalog), args.catalog)
    print("\n".join(summary_lines(generated.tasks)))
    print(f"wrote {path}")
    catalog = load_catalog_file(path)
    findings = generated.unreadable + files_findings(catalog, list(catalog))
    checked = [t.id for t in catalog if t.origin is not None] + [f.task for f in generated.unreadable]
    about = files_about(catalog)
    print(audit_text(findings, checked))
    print(duplicate_counts_text(about["duplicate instructions"]))
    print(f"recorded findings in {record_audit(path, 'files', about, findings, checked)}")
    return 0
