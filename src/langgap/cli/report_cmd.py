"""`langgap report`: the paper's tables and LangGap's diagnoses from stored runs."""

from __future__ import annotations

from langgap.errors import LangGapError
from langgap.report.formats import DIAGNOSIS_FORMATS, FORMATS


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("report", help="tables, diagnoses and plots from one or more runs")
    parser.add_argument(
        "run",
        metavar="RUN",
        nargs="*",
        help="run directories, side by side (the first is the reference for comparisons; one policy's runs on "
        "several catalogs get a column group per catalog)",
    )
    parser.add_argument(
        "--pool",
        action="append",
        default=[],
        metavar="LABEL=RUN,RUN...",
        help="replicate runs of one configuration (training seeds, say) counted together in one row of a pooled "
        "table, beside each run's successes; repeat it for more rows. With --pool, the report is that table "
        "(it shows no published rows)",
    )
    parser.add_argument("--compare", nargs="+", default=[], metavar="RUN2", help="more runs, side by side")
    parser.add_argument(
        "--format",
        choices=sorted(FORMATS),
        default="md",
        help="md: Markdown tables; latex: the same as LaTeX tables; json: every number; csv: one row per run, table "
        "and group (default: %(default)s)",
    )
    parser.add_argument(
        "--summary",
        action="store_true",
        help=f"only the diagnosis: the answer, success by dimension and what the policy did instead "
        f"(--format {' or '.join(DIAGNOSIS_FORMATS)})",
    )
    parser.add_argument(
        "--no-published",
        action="store_true",
        help="leave out the paper's published results (shown by default as reference rows, not re-run)",
    )
    parser.add_argument(
        "--allow-mismatch",
        action="store_true",
        help="pair runs episode by episode even when their protocol cards differ",
    )
    parser.add_argument(
        "--split",
        metavar="NAME[:K]",
        help="group every table's episodes by a stored split (`langgap splits list`, or a split file): its training "
        "tasks (with :K, its nested subset of K), its held-out tasks and the rest, instead of the tasks' own "
        "split (the per-episode table keeps theirs)",
    )
    parser.add_argument("--html", metavar="DIR", help="write the report as one self-contained page, DIR/index.html")
    parser.add_argument("--plots", metavar="DIR", help="write PNG figures to DIR")
    parser.add_argument("--episodes", metavar="FILE", help="write the per-episode table (.csv or .parquet)")
    parser.set_defaults(handler=run)


def _pools(entries: list[str]) -> dict[str, list[str]]:
    """`--pool LABEL=RUN,RUN...` entries as {label: runs}, in order."""
    pools: dict[str, list[str]] = {}
    for entry in entries:
        name, sep, runs = entry.partition("=")
        paths = [p for p in runs.split(",") if p]
        if not sep or not name or not paths:
            raise LangGapError(f"--pool takes LABEL=RUN,RUN...; got {entry!r}")
        if name in pools:
            raise LangGapError(f"--pool {name!r} is given twice: one row per label")
        pools[name] = paths
    return pools


# What a pooled report leaves out: these options are about the runs of a full report.
_NOT_POOLED = ("run", "compare", "summary", "no_published", "html", "plots", "episodes")


def run(args) -> int:
    from langgap.report import format_summary, load_runs, pooled_text, summarize

    if args.pool:
        given = [name for name in _NOT_POOLED if getattr(args, name)]
        if given:
            shown = ", ".join("RUN" if n == "run" else "--" + n.replace("_", "-") for n in given)
            raise LangGapError(f"--pool prints the pooled table only: name every run in a --pool, without {shown}")
        print(pooled_text(_pools(args.pool), args.format, allow_mismatch=args.allow_mismatch, split=args.split), end="")
        return 0
    if not args.run:
        raise LangGapError("name a run directory (or pool runs with --pool LABEL=RUN,RUN...)")
    paths = [*args.run, *args.compare]
    published = not args.no_published
    if args.summary and args.format not in DIAGNOSIS_FORMATS:
        raise LangGapError(
            f"--summary shows the diagnosis as {' or '.join(DIAGNOSIS_FORMATS)}; --format {args.format} holds "
            "every number of the full report: drop --summary"
        )
    # The text, --html and --plots are three views of one summary, read once.
    summary = summarize(load_runs(paths, split=args.split), allow_mismatch=args.allow_mismatch)
    print(format_summary(summary, args.format, published=published, diagnosis=args.summary), end="")
    if args.html:
        from langgap.report.html import write_html
        from langgap.report.published import load_published

        print(f"wrote {write_html(summary, load_published() if published else None, args.html)}")
    if args.plots:
        from langgap.report.plots import write_plots

        for path in write_plots(summary, args.plots):
            print(f"wrote {path}")
    if args.episodes:
        from langgap.report.export import write_episode_table

        print(f"wrote {write_episode_table(paths, args.episodes)}")
    return 0
