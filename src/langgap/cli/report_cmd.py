"""`langgap report`: the paper's tables and LangGap's diagnoses from stored runs."""

from __future__ import annotations

from langgap.errors import LangGapError
from langgap.report.formats import DIAGNOSIS_FORMATS, FORMATS


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("report", help="tables, diagnoses and plots from one or more runs")
    parser.add_argument(
        "run",
        metavar="RUN",
        nargs="+",
        help="run directories, side by side (the first is the reference for comparisons; one policy's runs on "
        "several catalogs get a column group per catalog)",
    )
    parser.add_argument("--compare", nargs="+", default=[], metavar="RUN2", help="more runs, side by side")
    parser.add_argument("--format", choices=sorted(FORMATS), default="md")
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
    parser.add_argument("--html", metavar="DIR", help="write the report as one self-contained page, DIR/index.html")
    parser.add_argument("--plots", metavar="DIR", help="write PNG figures to DIR")
    parser.add_argument("--episodes", metavar="FILE", help="write the per-episode table (.csv or .parquet)")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from langgap.report import diagnosis_text, load_runs, render, summarize

    paths = [*args.run, *args.compare]
    published = not args.no_published
    if args.summary:
        if args.format not in DIAGNOSIS_FORMATS:
            raise LangGapError(
                f"--summary shows the diagnosis as {' or '.join(DIAGNOSIS_FORMATS)}; --format {args.format} holds "
                "every number of the full report: drop --summary"
            )
        text = diagnosis_text(paths, args.format, published=published, allow_mismatch=args.allow_mismatch)
    else:
        text = render(paths, args.format, published=published, allow_mismatch=args.allow_mismatch)
    print(text, end="")
    if args.html or args.plots:
        summary = summarize(load_runs(paths), allow_mismatch=args.allow_mismatch)
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
