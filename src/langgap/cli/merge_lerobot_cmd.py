"""`langgap merge-lerobot`: merge LeRobot datasets (a LangGap export and `lerobot/libero`, say) with LeRobot's own
aggregation (in the LeRobot environment)."""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "merge-lerobot", help="merge LeRobot datasets into one with LeRobot's aggregation (same fps and features)"
    )
    parser.add_argument("out", metavar="OUT", help="the merged dataset's directory (must not exist)")
    parser.add_argument("sources", nargs="+", metavar="DATASET", help="LeRobot dataset directories (two or more)")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from langgap.demos.merge import merge_lerobot_datasets

    out = merge_lerobot_datasets(args.sources, args.out)
    print(f"merged {len(args.sources)} datasets into {out}")
    return 0
