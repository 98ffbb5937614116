"""`langgap export-hdf5`: write a collection in the robomimic/LIBERO HDF5 form (one file per task)."""

from __future__ import annotations

from langgap.errors import LangGapError


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "export-hdf5", help="write a collection's demonstrations as robomimic/LIBERO HDF5 files (DIR/hdf5)"
    )
    parser.add_argument("collection", metavar="DIR", help="a directory written by `langgap collect`")
    parser.add_argument("--out", metavar="OUT", help="output directory (default DIR/hdf5)")
    parser.add_argument("--images", action="store_true", help="also render both cameras by replaying the states (slow)")
    parser.add_argument(
        "--image-size", type=int, metavar="PX", help="with --images: their height and width (default: 256)"
    )
    parser.add_argument("--workers", type=int, help="with --images: rendering processes (default: 1; 0: here)")
    parser.add_argument("--force", action="store_true", help="replace existing HDF5 files")
    parser.add_argument(
        "--resume",
        action="store_true",
        help="keep the files an earlier export of this collection with these settings wrote; write the rest",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run, smoke=("workers",))


def run(args) -> int:
    from langgap.demos.hdf5 import write_hdf5
    from langgap.demos.render import checked_image_size

    for flag, value in (("--workers", args.workers), ("--image-size", args.image_size)):
        if value is not None and not args.images:
            raise LangGapError(f"{flag} is about rendered images: it needs --images")
    image_size = checked_image_size(args.image_size)
    export = write_hdf5(
        args.collection,
        out=args.out,
        images=args.images,
        image_size=image_size,
        workers=1 if args.workers is None else args.workers,
        progress=not args.no_progress,
        force=args.force,
        resume=args.resume,
    )
    kept = f" (kept {len(export.kept)} written before)" if args.resume else ""
    print(f"wrote {len(export.written)} HDF5 file(s) to {export.out}{kept}")
    return 0
