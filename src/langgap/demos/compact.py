"""The compact form of a collection: one NPZ per demonstration plus `collection.json`.

Layout of a collection directory::

    collection.json                       what was asked, per-task attempts/kept/success rate, versions
    demos/<task id>/<seed>.npz            one demonstration (arrays below)
    lerobot/                              the LeRobot v3 dataset (when LeRobot is installed)
    hdf5/                                 the robomimic/LIBERO HDF5 files (`langgap export-hdf5`)

A demonstration NPZ holds `states` (T, D) flattened sim states (the layout of LIBERO's init states),
`actions` (T, 7) executed, `labels` (T, 7) the oracle's commands (the
actions without `--noise`: the training targets), `robot_states` (T, 8), `body_pos`/`body_quat` the model's
body placements (fixtures are placed in the model, not the sim state), `priv/<key>` (T, ...) the privileged observations
(`eef_pos`, `eef_mat`, `gripper_qpos`, `body/<entity>`, `joint/<name>`), and `meta` (JSON: task id,
instruction, seed, distance of the start to the nearest fixed init state, hash of the
scene's fixture placements). Row t is the state before
action t; the episode starts from `reset` with that seed (which rebuilds the scene) and the 10
settle steps, which end in `states[0]`.
"""

from __future__ import annotations

import json
from collections.abc import Container
from pathlib import Path

import numpy as np

from langgap.demos.record import Demo
from langgap.errors import LangGapError

MANIFEST = "collection.json"
DEMOS_DIR = "demos"
LEROBOT_DIR = "lerobot"
HDF5_DIR = "hdf5"
FORMAT_VERSION = 1


class DemoFileError(LangGapError):
    """A collection directory or demonstration file is missing or malformed."""


def demo_path(root: Path, task_id: str, seed: int) -> Path:
    return Path(root) / DEMOS_DIR / task_id / f"{seed:08d}.npz"


def save_demo(root: Path, demo: Demo) -> Path:
    """Write one demonstration (atomically: a crash leaves no half-written file)."""
    path = demo_path(root, demo.task_id, demo.seed)
    path.parent.mkdir(parents=True, exist_ok=True)
    meta = {
        "task_id": demo.task_id,
        "instruction": demo.instruction,
        "seed": demo.seed,
        "nearest_init_distance": demo.nearest_init_distance,
        "scene_hash": demo.scene_hash,
    }
    arrays = {
        "states": demo.states,
        "actions": demo.actions,
        "labels": demo.labels,
        "robot_states": demo.robot_states,
        "body_pos": demo.body_pos,
        "body_quat": demo.body_quat,
        "meta": np.array(json.dumps(meta)),
        **{f"priv/{k}": v for k, v in demo.privileged.items()},
    }
    tmp = path.with_suffix(".tmp.npz")
    np.savez_compressed(tmp, **arrays)
    tmp.replace(path)
    return path


def load_demo(path: Path) -> Demo:
    """Read one demonstration file."""
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            return Demo(
                task_id=meta["task_id"],
                instruction=meta["instruction"],
                seed=int(meta["seed"]),
                states=data["states"],
                actions=data["actions"],
                labels=data["labels"],
                robot_states=data["robot_states"],
                nearest_init_distance=float(meta["nearest_init_distance"]),
                scene_hash=meta["scene_hash"],
                body_pos=data["body_pos"],
                body_quat=data["body_quat"],
                privileged={k[5:]: data[k] for k in data.files if k.startswith("priv/")},
            )
    except (OSError, KeyError, ValueError) as exc:
        raise DemoFileError(f"cannot read demonstration {path}: {exc}") from None


def short_tasks(manifest: dict) -> dict[str, int]:
    """The tasks of a collection's manifest that kept fewer demonstrations than it asked for, with how many
    each kept."""
    kept = {task: len(stats["kept"]) for task, stats in manifest["tasks"].items()}
    return {task: n for task, n in sorted(kept.items()) if n < manifest["demos"]}


def read_manifest(root: Path) -> dict:
    path = Path(root) / MANIFEST
    if not path.is_file():
        raise DemoFileError(
            f"{root} is not a demonstration collection (no {MANIFEST}); make one with `langgap collect`"
        )
    try:
        manifest = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise DemoFileError(f"cannot read {path}: {exc}") from None
    problem = _manifest_problem(manifest)
    if problem:
        raise DemoFileError(f"{path} is not a collection's manifest ({problem}); make one with `langgap collect`")
    return manifest


def _manifest_problem(manifest: object) -> str | None:
    """What keeps a parsed `collection.json` from being read as one (None: nothing): the fields every reader
    uses, the kept seeds of each task above all."""
    if not isinstance(manifest, dict):
        return f"a JSON {type(manifest).__name__}, not an object"
    missing = [key for key in ("catalog", "demos", "tasks") if key not in manifest]
    if missing:
        return f"no {', '.join(missing)}"
    tasks = manifest["tasks"]
    if not isinstance(tasks, dict) or not all(
        isinstance(s, dict) and isinstance(s.get("kept"), list) for s in tasks.values()
    ):
        return "`tasks` is not each task's kept seeds"
    return None


def write_manifest(root: Path, manifest: dict) -> None:
    path = Path(root) / MANIFEST
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n")
    tmp.replace(path)


def demo_files(root: Path, *, skip: Container[str] = ()) -> list[Path]:
    """All demonstration files of a collection, ordered by task id then seed (a stable dataset order), but those
    of the tasks in `skip`."""
    manifest = read_manifest(root)
    return [
        demo_path(root, task_id, seed)
        for task_id, stats in sorted(manifest["tasks"].items())
        if task_id not in skip
        for seed in stats["kept"]
    ]


def load_demos(roots: list[Path] | Path) -> list[Demo]:
    """Every demonstration of one or several collections, in `demo_files` order."""
    roots = [roots] if isinstance(roots, str | Path) else roots
    return [load_demo(path) for root in roots for path in demo_files(Path(root))]
