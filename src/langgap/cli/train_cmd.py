"""`langgap train`: `small-bc` on this machine (CPU), or the paper's LeRobot fine-tuning (`lerobot`, a GPU machine)."""

from __future__ import annotations

from pathlib import Path

from langgap.errors import LangGapError


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("train", help="train small-bc on demonstrations, or launch LeRobot fine-tuning")
    kinds = parser.add_subparsers(dest="train_kind", required=True, metavar="small-bc|lerobot")

    bc = kinds.add_parser("small-bc", help="train the small language-conditioned policy on CPU")
    bc.add_argument("--config", metavar="FILE", help="YAML file with any of the options below (flags override it)")
    bc.add_argument("--data", action="append", metavar="DIR", help="collection directory (repeatable)")
    bc.add_argument("--catalog", help="with --tasks: the catalog it selects from (default: langgap99)")
    bc.add_argument("--tasks", metavar="SELECTION", help="train on these tasks' demonstrations only (default: all)")
    bc.add_argument("--out", metavar="CKPT", help="checkpoint file to write (.safetensors)")
    bc.add_argument("--steps", type=int, help="optimisation steps (default: 3000)")
    bc.add_argument("--batch-size", type=int, help="frames per step (default: 128)")
    bc.add_argument("--lr", type=float, help="peak learning rate (default: 1e-3)")
    bc.add_argument("--seed", type=int, help="training seed (default: 0)")
    bc.add_argument("--threads", type=int, help="torch CPU threads (default: 2)")
    bc.add_argument("--loss", choices=("l1", "mse"), help="regression loss on the action chunk (default: l1)")
    bc.set_defaults(handler=run_small_bc, smoke=("steps", "collected_tasks"))

    lr = kinds.add_parser(
        "lerobot", help="launch lerobot-train (PEFT LoRA on pi0.5) for one of the paper's experiments"
    )
    lr.add_argument("config", metavar="CONFIG", help="experiment name (exp1..exp5) or YAML file")
    lr.add_argument(
        "--dataset-root", required=True, metavar="DIR", help="LeRobot dataset (e.g. a collection's lerobot/)"
    )
    lr.add_argument("--dataset-repo-id", default="local/langgap_demos", help="its repo id (default: %(default)s)")
    lr.add_argument("--output-dir", required=True, metavar="DIR", help="lerobot-train output directory")
    lr.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a config value (repeatable)")
    lr.add_argument("--dry-run", action="store_true", help="print the command line and exit")
    lr.set_defaults(handler=run_lerobot)


def _small_bc_config(args):
    import yaml

    from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
    from langgap.policies.small_bc.model import ModelConfig
    from langgap.training.train_small_bc import TrainConfig

    values: dict = {}
    if args.config:
        try:
            values = yaml.safe_load(Path(args.config).read_text()) or {}
        except (OSError, yaml.YAMLError) as exc:
            raise LangGapError(f"--config {args.config}: {exc}") from None
        if not isinstance(values, dict):
            raise LangGapError(f"{args.config}: expected a mapping of options")
    options = ("data", "catalog", "tasks", "out", "steps", "batch_size", "lr", "seed", "threads", "loss")
    for key in options:
        if getattr(args, key) is not None:
            values[key] = getattr(args, key)
    unknown = set(values) - {*options, "model"}
    if unknown:
        raise LangGapError(f"unknown small-bc option(s): {', '.join(sorted(unknown))}")
    if "catalog" in values and "tasks" not in values:
        raise LangGapError("--catalog only says where --tasks' selection is looked up: give --tasks too")
    for key in ("data", "out"):
        if not values.get(key):
            raise LangGapError(f"small-bc needs --{key}")
    data = values.pop("data")
    out = values.pop("out")
    catalog = values.pop("catalog", DEFAULT_CATALOG)
    selection = values.pop("tasks", None)
    tasks = tuple(t.id for t in load_catalog(catalog).select(selection)) if selection else None
    model = ModelConfig(**values.pop("model", {}))
    data = tuple(str(d) for d in ([data] if isinstance(data, str) else data))
    return TrainConfig(data=data, tasks=tasks, model=model, **values), out


def run_small_bc(args) -> int:
    from langgap.training.train_small_bc import train

    config, out = _small_bc_config(args)
    facts = train(config, out)
    print(
        f"trained on {facts['demos']} demonstrations ({facts['frames']} frames) of {len(facts['tasks'])} tasks "
        f"in {facts['train_time_s']:.0f}s; wrote {out}"
    )
    return 0


def run_lerobot(args) -> int:
    from langgap.cli.policy_options import parse_key_values
    from langgap.training.lerobot_train import launch, load_experiment, train_command

    experiment = load_experiment(args.config, overrides=parse_key_values(args.set, "--set"))
    command = train_command(
        experiment, dataset_root=args.dataset_root, repo_id=args.dataset_repo_id, output_dir=args.output_dir
    )
    if args.dry_run:
        import shlex

        print(shlex.join(command))
        return 0
    return launch(command)
