"""`langgap train`: `small-bc` and `small-vla` on this machine (CPU), or the paper's LeRobot fine-tuning (`lerobot`,
a GPU machine)."""

from __future__ import annotations

from pathlib import Path

from langgap.errors import LangGapError
from langgap.policies.text import VOCABULARIES
from langgap.training import LOSSES


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "train", help="train small-bc or small-vla on demonstrations, or launch LeRobot fine-tuning"
    )
    kinds = parser.add_subparsers(dest="train_kind", required=True, metavar="small-bc|small-vla|lerobot")

    bc = kinds.add_parser("small-bc", help="train the small language-conditioned policy on simulator state (CPU)")
    _add_training_flags(bc, data="collection directory (repeatable)")
    bc.set_defaults(handler=run_small_bc, smoke=("steps", "collected_tasks"))
    vla = kinds.add_parser(
        "small-vla", help="train the small vision-language policy on camera images (CPU, or a GPU unchanged)"
    )
    _add_training_flags(vla, data="collection directory with images (`langgap export-hdf5 DIR --images`; repeatable)")
    vla.set_defaults(handler=run_small_vla, smoke=("steps", "collected_tasks"))

    lr = kinds.add_parser(
        "lerobot", help="launch lerobot-train for one of the paper's experiments (`langgap experiment run` chains it)"
    )
    lr.add_argument("config", metavar="CONFIG", help="experiment name (exp1..exp5) or YAML file")
    lr.add_argument(
        "--dataset-root", required=True, metavar="DIR", help="LeRobot dataset (e.g. a collection's lerobot/)"
    )
    lr.add_argument("--dataset-repo-id", default="local/langgap_demos", help="its repo id (default: %(default)s)")
    lr.add_argument("--output-dir", required=True, metavar="DIR", help="lerobot-train output directory")
    lr.add_argument("--policy", default="pi05", help="pi05 (the paper's), pi0, smolvla, act, or a recipe YAML file")
    lr.add_argument("--tuning", help="which parameters train (`langgap experiment list` shows each policy's)")
    lr.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a lerobot-train option (repeatable)")
    lr.add_argument("--dry-run", action="store_true", help="print the command line and exit")
    lr.set_defaults(handler=run_lerobot)


def _add_training_flags(parser, *, data: str) -> None:
    """The flags `small-bc` and `small-vla` share."""
    parser.add_argument("--config", metavar="FILE", help="YAML file with any of the options below (flags override it)")
    parser.add_argument("--data", action="append", metavar="DIR", help=data)
    parser.add_argument("--catalog", help="with --tasks: the catalog it selects from (default: langgap99)")
    parser.add_argument("--tasks", metavar="SELECTION", help="train on these tasks' demonstrations only (default: all)")
    parser.add_argument("--out", metavar="CKPT", help="checkpoint file to write (.safetensors)")
    parser.add_argument("--steps", type=int, help="optimisation steps (default: 3000)")
    parser.add_argument("--batch-size", type=int, help="frames per step (default: 128)")
    parser.add_argument("--lr", type=float, help="peak learning rate (default: 1e-3)")
    parser.add_argument("--seed", type=int, help="training seed (default: 0)")
    parser.add_argument("--threads", type=int, help="torch CPU threads (default: 2)")
    parser.add_argument("--loss", choices=LOSSES, help="regression loss on the action chunk (default: l1)")
    parser.add_argument("--device", help="where the model trains: cpu (the default) or a GPU, e.g. cuda")
    parser.add_argument(
        "--vocabulary",
        choices=VOCABULARIES,
        help="the model's words: every shipped catalog's sentences (the default), or only the training data's "
        "(how earlier checkpoints were trained)",
    )


def _training_config(args, model_config: type):
    """The `TrainConfig` of the flags over the `--config` file, and the checkpoint to write; `model_config`: the
    model's config class (the file's `model` mapping)."""
    import yaml

    from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
    from langgap.training.loop import TrainConfig

    values: dict = {}
    if args.config:
        try:
            values = yaml.safe_load(Path(args.config).read_text()) or {}
        except (OSError, yaml.YAMLError) as exc:
            raise LangGapError(f"--config {args.config}: {exc}") from None
        if not isinstance(values, dict):
            raise LangGapError(f"{args.config}: expected a mapping of options")
    how = ("steps", "batch_size", "lr", "seed", "threads", "loss", "device", "vocabulary")
    options = ("data", "catalog", "tasks", "out", *how)
    for key in options:
        if getattr(args, key) is not None:
            values[key] = getattr(args, key)
    unknown = set(values) - {*options, "model"}
    if unknown:
        raise LangGapError(f"unknown {args.train_kind} option(s): {', '.join(sorted(unknown))}")
    if "catalog" in values and "tasks" not in values:
        raise LangGapError("--catalog only says where --tasks' selection is looked up: give --tasks too")
    for key in ("data", "out"):
        if not values.get(key):
            raise LangGapError(f"{args.train_kind} needs --{key}")
    data = values.pop("data")
    out = values.pop("out")
    catalog = values.pop("catalog", DEFAULT_CATALOG)
    selection = values.pop("tasks", None)
    tasks = tuple(t.id for t in load_catalog(catalog).select(selection)) if selection else None
    try:
        model = model_config(**values.pop("model")) if "model" in values else None
    except TypeError as exc:
        raise LangGapError(f"{args.config}: model: {exc}") from None
    data = tuple(str(d) for d in ([data] if isinstance(data, str) else data))
    return TrainConfig(data=data, tasks=tasks, model=model, **values), out


def run_small_bc(args) -> int:
    from langgap.policies.small_bc.model import ModelConfig
    from langgap.training.train_small_bc import train

    return _trained(train, *_training_config(args, ModelConfig))


def run_small_vla(args) -> int:
    from langgap.policies.small_vla.model import VisionConfig
    from langgap.training.train_small_vla import train

    return _trained(train, *_training_config(args, VisionConfig))


def _trained(train, config, out) -> int:
    facts = train(config, out)
    print(
        f"trained on {facts['demos']} demonstrations ({facts['frames']} frames) of {len(facts['tasks'])} tasks "
        f"in {facts['train_time_s']:.0f}s; wrote {out}"
    )
    return 0


def run_lerobot(args) -> int:
    from langgap.cli.policy_options import parse_key_values
    from langgap.training.lerobot_train import launch, load_experiment, load_recipe, train_command, train_options

    experiment = load_experiment(args.config)
    options = train_options(
        experiment, load_recipe(args.policy), tuning=args.tuning, overrides=parse_key_values(args.set, "--set")
    )
    command = train_command(
        options,
        dataset_root=args.dataset_root,
        repo_id=args.dataset_repo_id,
        output_dir=args.output_dir,
        job_name=f"langgap_{experiment.name}",
    )
    if args.dry_run:
        import shlex

        print(shlex.join(command))
        return 0
    return launch(command)
