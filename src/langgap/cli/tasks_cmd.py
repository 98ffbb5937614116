"""`langgap tasks list`, `show`, `gate`, `replay` and `audit`."""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import asdict
from pathlib import Path

from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
from langgap.catalog.naming import SUITE_SHORT
from langgap.catalog.task import DEFAULT_STYLE, DIMENSIONS, RUN_STYLES, SPLITS, Task
from langgap.catalog.verdicts import SAME_TRIAL, verdict_counts
from langgap.errors import LangGapError
from langgap.stack import SUITES
from langgap.vocabulary import SWITCH, TaskKind, Verdict, switch_step, words


def add_catalog_option(parser) -> None:
    """`--catalog`, shared by every verb that works on tasks."""
    parser.add_argument(
        "--catalog", default=DEFAULT_CATALOG, help="catalog name or registry file (default: %(default)s)"
    )


def add_catalog_options(parser) -> None:
    """`--catalog` and `--style`, for verbs that also show or send instructions."""
    add_catalog_option(parser)
    parser.add_argument(
        "--style",
        default=DEFAULT_STYLE,
        choices=RUN_STYLES,
        help="which sentence policies are sent: LIBERO's wording, the paper's, or the one the task's own "
        "benchmark runner sends (package: LIBERO-PRO's and LIBERO-Plus's task.language; default: %(default)s)",
    )


# What a task selection is (`Catalog.select`; docs/catalogs.md, "Selecting tasks"), for every `--tasks`'s help.
SELECTION_HELP = (
    "terms joined by commas (any of them), & (all of them), ! before one (not it): a task id, a glob over ids "
    "(spatial/s0/*), a suite (spatial, object, goal, libero10), original or extended, a dimension (change_object, "
    "change_target, ...), a split (train, heldout), feasible or rejected, paper:N, all; e.g. 'spatial&heldout'"
)


def _add_tasks_option(parser) -> None:
    parser.add_argument(
        "--tasks",
        metavar="SELECTION",
        default="all",
        help=f"the tasks: {SELECTION_HELP} (default: every task, gated or not)",
    )


def _suite(name: str) -> str:
    """A suite named in full (`libero_spatial`) or as task ids and selections name it (`spatial`)."""
    return {short: suite for suite, short in SUITE_SHORT.items()}.get(name, name)


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("tasks", help="list and inspect tasks")
    verbs = parser.add_subparsers(dest="tasks_verb", required=True, metavar="list|show|gate|replay|audit")

    listing = verbs.add_parser("list", help="list tasks, optionally filtered")
    add_catalog_options(listing)
    listing.add_argument(
        "--suite",
        type=_suite,
        choices=SUITES,
        help=f"only this suite's tasks ({', '.join(SUITE_SHORT.values())} name them too)",
    )
    listing.add_argument(
        "--kind", choices=words(TaskKind), help="only the LIBERO originals, or only the extended tasks"
    )
    listing.add_argument("--dimension", choices=DIMENSIONS, help="only the tasks of this dimension")
    listing.add_argument(
        "--split",
        choices=[s for s in SPLITS if s != TaskKind.ORIGINAL] + [TaskKind.ORIGINAL.value],
        help="only the extended tasks a policy may train on (train), those held out, or the originals",
    )
    _add_tasks_option(listing)
    listing.add_argument("--json", action="store_true", help="print a JSON array of task objects")
    listing.set_defaults(handler=run_list)

    show = verbs.add_parser("show", help="show one task with its BDDL file and init-state source")
    add_catalog_options(show)
    show.add_argument("id", help="task id (see `langgap tasks list`)")
    show.add_argument("--json", action="store_true", help="print the task as a JSON object")
    show.add_argument(
        "--bddl", action="store_true", help="print only the task's BDDL file (a start for a task of your own)"
    )
    show.set_defaults(handler=run_show)

    gate = verbs.add_parser(
        "gate", help="the feasibility gate's verdicts counted per suite and dimension (what is proven)"
    )
    add_catalog_option(gate)
    _add_tasks_option(gate)
    gate.add_argument("--markdown", action="store_true", help="print a Markdown table")
    gate.add_argument(
        "--condition",
        action="append",
        metavar=f"{SWITCH}K",
        help=f"count the switch gate's verdicts at K instead (repeatable; `langgap validate --condition {SWITCH}K`)",
    )
    gate.set_defaults(handler=run_gate)

    replay = verbs.add_parser(
        "replay",
        help="replay every stored demonstration the selected tasks' verdicts rest on; exit 1 if one does not reach "
        "its goal at its recorded step",
    )
    add_catalog_option(replay)
    _add_tasks_option(replay)
    replay.add_argument(
        "--remake",
        action="store_true",
        help="where a file does not replay (another physics stack, e.g. BLAS kernel), play the candidate that found "
        "it (its found_by) again and write what it records now over the file, once that replays",
    )
    replay.set_defaults(handler=run_replay, smoke=("tasks",))

    audit = verbs.add_parser(
        "audit",
        help="LangGap's checks of a catalog's tasks (a package's files, their starts; LangGap's own sentences against "
        "their goals): each finding, counted",
    )
    add_catalog_option(audit)
    _add_tasks_option(audit)
    audit.add_argument(
        "--starts",
        type=int,
        default=0,
        metavar="K",
        help="also run the simulator checks (t0 state equals the source's, goal not true at t0) on init states "
        "0..K-1 (50: all); without it, the simulator checks' recorded findings are shown",
    )
    audit.add_argument(
        "--references",
        type=int,
        default=0,
        metavar="K",
        help="also resolve each sentence's referring expressions on init states 0..K-1, from the robot's viewpoint, "
        "the camera's (its raw render) and in the policy's image (does it pick the goal's objects?); without it, "
        "the recorded findings are shown",
    )
    audit.add_argument("--examples", type=int, default=3, metavar="N", help="examples shown per finding")
    audit.add_argument("--record", action="store_true", help="record the checks that ran beside the registry")
    audit.add_argument(
        "--html",
        metavar="DIR",
        help="also write the audit as one self-contained page, DIR/index.html: each finding with its evidence "
        "and the command that reproduces it",
    )
    audit.set_defaults(handler=run_audit, smoke=("tasks", "starts", "references"))


def _filtered(args) -> list[Task]:
    tasks = load_catalog(args.catalog).select(args.tasks)
    for field in ("suite", "kind", "dimension", "split"):
        wanted = getattr(args, field)
        if wanted:
            tasks = [t for t in tasks if getattr(t, field) == wanted]
    return tasks


def run_list(args) -> int:
    tasks = _filtered(args)
    if args.json:
        print(json.dumps([t.to_dict(args.style) for t in tasks], indent=1))
        return 0
    width = max((len(t.id) for t in tasks), default=2)
    verdict = max(map(len, Verdict))
    print(
        f"{'id':<{width}}  {'paper':>5}  {'dimension':<19}  {'split':<8}  {'gate':<{verdict}}  "
        f"instruction ({args.style})"
    )
    for t in tasks:
        paper = "-" if t.paper_id is None else str(t.paper_id)
        gate = "-" if t.gate is None else t.gate.verdict
        print(
            f"{t.id:<{width}}  {paper:>5}  {t.dimension:<19}  {t.split:<8}  {gate:<{verdict}}  "
            f"{t.instruction(args.style)}"
        )
    by_kind = Counter(t.kind for t in tasks)
    by_dim = Counter(t.dimension for t in tasks if t.kind == TaskKind.EXTENDED)
    rejected = [t.gate.verdict for t in tasks if not t.feasible]
    print(
        f"\n{len(tasks)} tasks: "
        + ", ".join(f"{by_kind[kind]} {kind}" for kind in TaskKind)
        + (" (" + ", ".join(f"{d} {n}" for d, n in sorted(by_dim.items())) + ")" if by_dim else "")
        + f"; {len(rejected)} rejected by the feasibility gate"
        + (f" ({verdict_counts(rejected, always=())})" if rejected else "")
    )
    return 0


def run_show(args) -> int:
    from langgap.catalog import files

    catalog = load_catalog(args.catalog)
    task = catalog.get(args.id)
    if args.bddl:
        print(files.task_bddl_path(task).read_text(encoding="utf-8"), end="")
        return 0
    info = task.to_dict(args.style)
    info["bddl"] = str(files.task_bddl_path(task))
    info["scene_bddl"] = str(files.scene_bddl_path(task))
    info["init_states"] = {
        "file": str(files.init_states_path(task)),
        "count": int(files.init_states(task).shape[0]),
        "from": f"LIBERO {task.suite} task {task.scene_index} ({task.scene_task})"
        if task.origin is None or task.origin.init_runs == "source"
        else f"{task.origin.package} {task.origin.version}, for its perturbation of {task.scene_task}",
    }
    info["siblings"] = [t.id for t in catalog.siblings(task) if t.id != task.id]
    info["findings"] = _recorded_findings(args.catalog, task.id)
    switch = _recorded_switch_verdicts(args.catalog, task.id)
    info["switch_gate"] = {k: {**asdict(v), "rate": v.rate} for k, v in switch.items()}
    if args.json:
        print(json.dumps(info, indent=1))
        return 0
    for key in ("id", "catalog", "suite", "kind", "dimension", "split", "source", "paper_id", "max_steps"):
        print(f"{key:<12} {info[key]}")
    print(f"{'instruction':<12} {info['instruction']!r}  ({args.style} style)")
    for style, text in task.instructions.items():
        print(f"{'':<12} {style}: {text!r}")
    print(f"{'goal':<12} {' '.join(info['goal'])}")
    print(f"{'bddl':<12} {info['bddl']}")
    if task.origin is not None:
        print(f"{'read':<12} from {task.origin.package} {task.origin.version}, unchanged")
    elif task.kind == TaskKind.EXTENDED:
        print(f"{'generated':<12} from {info['scene_bddl']} (only language, obj_of_interest and goal differ)")
    print(f"{'init states':<12} {info['init_states']['count']} from {info['init_states']['from']}")
    print(f"{'':<12} {info['init_states']['file']}")
    print(f"{'siblings':<12} {len(info['siblings'])} other task(s) on the same scene")
    for sibling in info["siblings"]:
        print(f"{'':<12} {sibling}")
    for line in _gate_lines(task.gate):
        print(f"{'gate':<12} {line}")
    print(f"{'evidence:':<12} {task.evidence}")
    for condition, verdict in switch.items():
        print(f"{'switch gate':<12} {condition}: {_gate_lines(verdict)[0]}")
    for note in task.notes:
        print(f"{'note':<12} {note}")
    if task.origin is not None:
        origin = task.origin
        print(f"{'origin':<12} {origin.package} {origin.version}: {origin.file} (sha256 {origin.sha256[:16]}…)")
        print(f"{'':<12} init states shipped: {origin.init_file} (runs: {origin.init_runs})")
    for finding in info["findings"]:
        print(f"{'finding':<12} {finding['name']}: {finding['detail']}")
    return 0


def _recorded_switch_verdicts(catalog: str, task_id: str) -> dict:
    """The task's switch verdicts (`switch:K` -> verdict, in K order) from the catalog's switch verdict file."""
    from langgap.catalog.catalog import registry_path
    from langgap.catalog.switch_verdicts import read_switch_verdicts

    by_k = read_switch_verdicts(registry_path(catalog)).get(task_id, {})
    return dict(sorted(by_k.items(), key=lambda item: switch_step(item[0]) or 0))


def run_gate(args) -> int:
    from langgap.gate.coverage import coverage_table, gate_counts, stacks_text

    tasks = load_catalog(args.catalog).select(args.tasks)
    if args.condition:
        return _switch_gate_counts(args, tasks)
    print(coverage_table(gate_counts(tasks), markdown=args.markdown))
    if (stacks := stacks_text(tasks)) is not None:
        print(f"\n{stacks}" if args.markdown else stacks)
    ungated = sum(t.gate is None for t in tasks)
    if ungated:
        print(
            f"{ungated} of {len(tasks)} task(s) not gated: {Verdict.UNPROVEN} until the gate runs "
            f"(langgap validate --catalog {args.catalog} --record)"
        )
    taken = [t for t in tasks if t.gate is not None and t.gate.inherited_from]
    if taken:
        sources = {t.gate.inherited_from for t in taken}
        print(
            f"{len(taken)} of {len(tasks)} verdict(s) taken from {len(sources)} task(s) of another catalog, with "
            f"{SAME_TRIAL} (the oracle column counts a source's episodes once per task that takes its verdict)"
        )
    return 0


def run_replay(args) -> int:
    from langgap.gate.demonstrations import replay_verdicts

    tasks = load_catalog(args.catalog).select(args.tasks)
    checks = []
    for check in replay_verdicts(tasks, args.catalog):
        outcome = f"FAIL: {check.error}" if check.error else f"reaches its goal at step {check.steps}, as recorded"
        if check.error and args.remake:
            check, outcome = _remade(check, outcome)
        checks.append(check)
        print(f"{check.task_id} init {check.init_index}: {outcome}", flush=True)
    if not checks:
        print(f"no verdict of the {len(tasks)} selected task(s) rests on a stored demonstration")
        return 0
    failed = sum(bool(c.error) for c in checks)
    shown = len({c.task_id for c in checks})
    print(f"{len(checks) - failed}/{len(checks)} stored demonstration(s) of {shown} task(s) replay to their goals")
    return 1 if failed else 0


def _remade(check, failure: str):
    """`tasks replay --remake` on a file that failed: the check and its line once remade (`remake`)."""
    from dataclasses import replace

    from langgap.gate.demonstrations import Demonstration, DemonstrationError, save_verified
    from langgap.gate.search import remake

    catalog = load_catalog(check.catalog)
    old = Demonstration.load(check.path)
    remade = remake(old, catalog)
    if remade is None:
        return check, f"{failure}; neither its actions nor its finder ({old.found_by}) do the task here: search again"
    new, how = remade
    try:
        save_verified(new, check.path, catalog)
    except DemonstrationError as exc:
        return check, f"{failure}; remade from its {how}, but {exc}"
    line = f"remade from its {how}: reaches its goal at step {new.steps} (was {old.steps})"
    return replace(check, steps=new.steps, error=""), line


def _switch_gate_counts(args, tasks: list[Task]) -> int:
    """`tasks gate --condition switch:K`: the switch verdicts at each K, counted as the plain ones are."""
    import dataclasses

    from langgap.catalog.catalog import registry_path
    from langgap.catalog.switch_verdicts import read_switch_verdicts
    from langgap.engine.plan import without_switch_source
    from langgap.gate.coverage import coverage_table, gate_counts
    from langgap.gate.switch import switch_conditions

    verdicts = read_switch_verdicts(registry_path(args.catalog))
    catalog = load_catalog(args.catalog)
    alone = set(without_switch_source(tasks, catalog))
    for index, condition in enumerate(switch_conditions(args.condition)):
        at_k = [dataclasses.replace(t, gate=verdicts.get(t.id, {}).get(condition)) for t in tasks]
        print(("\n" if index else "") + f"{condition}:")
        print(coverage_table(gate_counts(at_k), markdown=args.markdown))
        ungated = sum(t.gate is None and t.id not in alone for t in at_k)
        if ungated:
            print(
                f"{ungated} of {len(tasks)} task(s) not gated at {condition}: {Verdict.UNPROVEN} until the switch gate "
                "runs "
                f"(langgap validate --catalog {args.catalog} --condition {condition} --record)"
            )
        if alone:
            print(
                f"{len(alone)} of {len(tasks)} task(s) have no other task in their scene to start under: never switched"
            )
    return 0


def run_audit(args) -> int:
    from langgap.audit import audit
    from langgap.audit.findings import audit_text, duplicate_counts_text

    found = audit(
        args.catalog,
        args.tasks,
        starts=args.starts,
        references=args.references,
        record=args.record,
        progress=lambda line: print(line, flush=True),
    )
    print(audit_text(list(found.findings), found.checked, examples=args.examples))
    if found.package_ids:
        print(duplicate_counts_text(found.ran["files"]["duplicate instructions"]))
    if args.html:
        print(f"wrote {_write_audit_page(args, found)}")
    if found.recorded is not None:
        print(f"recorded findings in {found.recorded}")
    return 0


def _write_audit_page(args, found) -> Path:
    """Write the audit page (`--html DIR`) of `found` (an `AuditResult`) and return its path."""
    from langgap.atomic import write_text_atomically
    from langgap.audit.page import audit_data, audit_page
    from langgap.catalog.catalog import catalog_hash

    data = audit_data(
        found.catalog,
        args.catalog,
        catalog_hash(args.catalog),
        list(found.findings),
        found.checked,
        found.about | found.ran,
    )
    path = Path(args.html) / "index.html"
    try:
        write_text_atomically(path, audit_page(data))
    except OSError as exc:
        raise LangGapError(f"cannot write {path}: {exc.strerror}") from None
    return path


def _gate_lines(gate) -> list[str]:
    """The feasibility verdict of a task as `tasks show` prints it (its evidence follows on a line of its own)."""
    if gate is None:
        return ["not validated (langgap validate --record)"]
    where = f" on init states 0–{gate.inits - 1}" if gate.inits else ""
    verdict = str(gate.verdict)
    if gate.demonstrated:
        shown = ", ".join(map(str, gate.demonstrated_inits))
        verdict += f" (searched demonstrations do init state(s) {shown}, which the oracle failed)"
    lines = [f"oracle {gate.successes}/{gate.episodes}{where}: {verdict}"]
    if gate.reason:
        lines.append(f"why: {gate.reason}")
    if gate.failed_inits:
        lines.append(f"oracle failed on init states {', '.join(map(str, gate.failed_inits))}")
    if gate.made_by:
        lines.append(f"made by: {gate.made_by}")
    if gate.other_stack:
        lines.append(f"made on another physics stack than the installed one: {', '.join(gate.other_stack)}")
    return lines


def _recorded_findings(catalog: str, task_id: str) -> list[dict]:
    """What the recorded audit found in one task (empty without an audit)."""
    from langgap.audit.findings import read_audit
    from langgap.catalog.catalog import registry_path

    return [{"name": f.name, "detail": f.detail} for f in read_audit(registry_path(catalog))[1] if f.task == task_id]
