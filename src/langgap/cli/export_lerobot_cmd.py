"""`langgap export-lerobot`: write a collection's LeRobot v3 dataset (in the LeRobot environment)."""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "export-lerobot", help="render a collection's demonstrations into a LeRobot v3 dataset (DIR/lerobot)"
    )
    parser.add_argument("collection", metavar="DIR", help="a directory written by `langgap collect`")
    parser.add_argument("--workers", type=int, default=1, help="rendering processes (0: here)")
    parser.add_argument("--image-size", type=int, metavar="PX", help="the images' height and width (default: 256)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run, smoke=("workers",))


def run(args) -> int:
    from langgap.demos.export import write_lerobot_dataset
    from langgap.demos.render import checked_image_size

    image_size = checked_image_size(args.image_size)
    # No --repo-id: LeRobot keeps a dataset's repo id only to upload it, and nothing is uploaded.
    path = write_lerobot_dataset(
        args.collection, workers=args.workers, image_size=image_size, progress=not args.no_progress
    )
    print(f"wrote the LeRobot dataset to {path}")
    return 0
