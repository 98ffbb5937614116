"""The robomimic/LIBERO HDF5 form of a collection: one file per task, laid out as LIBERO's own datasets.

`<out>/<task id, '/' replaced by '__'>_demo.hdf5`::

    data                      attrs: problem_info (JSON: language_instruction = the demos' catalog instruction,
                              problem_name, domain_name), env_args (JSON: robomimic env meta), bddl_file_content,
                              num_demos, total (frames), langgap_task_id, langgap_catalog, langgap_version,
                              langgap_collection (JSON: the collection's settings and this task's counts),
                              physics (JSON: the simulation stack), image_orientation (with images)
    data/demo_<i>             i from 0, in the collection's order;
                              attrs: num_samples, seed, nearest_init_distance, scene_hash, init_state (= states[0])
        actions   (T, 7)      the executed actions (with `collect --noise`): what a replay applies
        labels    (T, 7)      the oracle's clean commands: the training targets (DART)
        states    (T, D)      flattened sim states (LIBERO's init-state layout); row t is before action t
        robot_states (T, 8)   LangGap's 8-D state (eef pos, eef axis-angle, two finger joints)
        rewards, dones (T,)   uint8, 1 at the last step only (every demonstration succeeds there)
        body_pos, body_quat   the model's body placements (fixtures): a replay writes them into the model
        obs/<key>             the privileged observations, '/' replaced by '__' (attr langgap_key: the original)
        obs/agentview_rgb, obs/eye_in_hand_rgb   (T, H, W, 3) uint8, gzip (with `images`)

Images are rendered by replaying the recorded states (`langgap.demos.render`), upright like every LangGap
image; LIBERO's own files hold the raw render, upside down (see the `image_orientation` attribute).
"""

from __future__ import annotations

import functools
import itertools
import json
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from langgap import stack
from langgap.catalog import files
from langgap.catalog.catalog import load_catalog
from langgap.catalog.task import Task
from langgap.demos.compact import HDF5_DIR, DemoFileError, demo_files, read_manifest
from langgap.demos.record import Demo
from langgap.demos.render import IMAGE_ORIENTATION, IMAGE_SIZE, iter_demos
from langgap.errors import DependencyNotInstalled, LangGapError, ParameterError
from langgap.version import code_version
from langgap.video import CONTROL_HZ

# LangGap camera -> LIBERO's observation key.
IMAGE_KEYS = {"agentview": "agentview_rgb", "robot0_eye_in_hand": "eye_in_hand_rgb"}
# LIBERO's ControlEnv defaults, which TaskEnv builds with; robomimic's env meta records them.
ROBOT = "Panda"
CONTROLLER = "OSC_POSE"
ROBOSUITE_ENV_TYPE = 1  # robomimic's EnvType.ROBOSUITE_TYPE (LIBERO's files say the same)
GZIP_LEVEL = 4


@dataclass(frozen=True)
class HDF5Export:
    """What `write_hdf5` did: the directory, the files it wrote and those it kept (`resume`), in task order."""

    out: Path
    written: list[Path]
    kept: list[Path]


def require_h5py():
    """The h5py module, or a DependencyNotInstalled that says how to install it."""
    try:
        import h5py
    except ImportError:
        raise DependencyNotInstalled(
            "the HDF5 export needs h5py: pip install 'langgap[hdf5]' (./setup.sh installs it)"
        ) from None
    return h5py


def hdf5_path(out: str | Path, task_id: str) -> Path:
    """The HDF5 file of `task_id` in `out` (LIBERO's `<name>_demo.hdf5`; task ids hold '/')."""
    return Path(out) / f"{task_id.replace('/', '__')}_demo.hdf5"


def obs_name(key: str) -> str:
    """The HDF5 dataset name of a privileged key: '/' would make nested groups, which robomimic does not read."""
    return key.replace("/", "__")


def write_hdf5(
    root: str | Path,
    *,
    out: str | Path | None = None,
    images: bool = False,
    image_size: int = IMAGE_SIZE,
    workers: int = 1,
    progress: bool = True,
    force: bool = False,
    resume: bool = False,
) -> HDF5Export:
    """Write the collection at `root` as one HDF5 file per task in `out` (default `root/hdf5`).

    `images` renders both cameras (`image_size` square) by replaying the recorded states, in `workers` processes
    (0: here).
    Each file is written under a temporary name and renamed when complete, so a file with its final name is
    whole. Existing files are replaced only with `force`; with `resume`, those written from this collection
    with these settings are kept and only the missing ones are written (an interrupted export with images
    continues instead of rendering everything again). Without either, any existing file stops the export
    before anything is written; so does, with `resume`, one written from elsewhere or with other settings.
    """
    if force and resume:
        raise ParameterError("{force} replaces the existing files and {resume} keeps them: pass one of them")
    h5py = require_h5py()
    root = Path(root)
    manifest = read_manifest(root)
    out = Path(out) if out is not None else root / HDF5_DIR
    targets = {task_id: hdf5_path(out, task_id) for task_id, stats in manifest["tasks"].items() if stats["kept"]}
    if not targets:
        raise LangGapError(f"{root} holds no demonstrations")
    settings = {key: value for key, value in manifest.items() if key != "tasks"}
    collections = {task_id: {**settings, "task": manifest["tasks"][task_id]} for task_id in targets}
    existing = {task_id: path for task_id, path in targets.items() if path.exists()}
    if existing and not (force or resume):
        more = f" (and {len(existing) - 1} more)" if len(existing) > 1 else ""
        raise ParameterError(
            "{path} exists already{more}; pass {resume} to keep what is written and add the rest, or {force} to "
            "overwrite",
            path=next(iter(existing.values())),
            more=more,
        )
    stored_size = image_size if images else 0  # what a file records: 0 for one without images
    kept = {}
    if resume:
        for task_id, path in existing.items():
            _check_resumable(h5py, path, collections[task_id], stored_size)
        kept = existing
    catalog = load_catalog(manifest["catalog"])
    out.mkdir(parents=True, exist_ok=True)
    paths = demo_files(root, skip=kept)
    demos = iter_demos(
        manifest["catalog"], paths, render=images, workers=workers, progress=progress, image_size=image_size
    )
    written = []
    # `paths` is ordered by task, so each task's demonstrations arrive together.
    for task_id, group in itertools.groupby(demos, key=lambda item: item[0].task_id):
        write = functools.partial(
            _write_task,
            task=catalog.get(task_id),
            demos=group,
            collection=collections[task_id],
            image_size=stored_size,
        )
        _write_atomically(h5py, targets[task_id], write)
        written.append(targets[task_id])
    return HDF5Export(out=out, written=written, kept=sorted(kept.values()))


def _check_resumable(h5py, path: Path, collection: dict, image_size: int) -> None:
    """Raise unless the file at `path` was exported from this task of `collection` with `image_size` (0: none)."""
    try:
        with h5py.File(path, "r") as f:
            attrs = f["data"].attrs
            written_from = json.loads(attrs["langgap_collection"])
            env_kwargs = json.loads(attrs["env_args"])["env_kwargs"]
    except (OSError, KeyError, ValueError) as exc:
        raise ParameterError(
            "cannot resume: {path} is not a LangGap HDF5 export ({exc}); pass {force} to replace it", path=path, exc=exc
        ) from None
    written_size = env_kwargs.get("camera_heights", 0)
    if written_from != json.loads(json.dumps(collection)):  # compared as stored: JSON has no tuples
        raise ParameterError(
            "cannot resume: {path} was exported from another collection, or from this one before it changed; "
            "pass {force} to replace it",
            path=path,
        )
    if written_size != image_size:
        raise ParameterError(
            "cannot resume: {path} has {written}, this export asks for {asked}; pass {force} to replace it",
            path=path,
            written=_images(written_size),
            asked=_images(image_size),
        )


def _images(size: int) -> str:
    return f"{size} px images" if size else "no images"


def _write_atomically(h5py, path: Path, write) -> None:
    # A killed export leaves at most a `.partial` file, never one with the final name.
    partial = path.with_name(path.name + ".partial")
    try:
        with h5py.File(partial, "w") as f:
            write(f)
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


def _write_task(
    f, *, task: Task, demos: Iterable[tuple[Demo, dict[str, np.ndarray]]], collection: dict, image_size: int
) -> None:
    """One task's file; `image_size` 0: without images."""
    data = f.create_group("data")
    instruction = None
    total = 0
    for index, (demo, frames) in enumerate(demos):
        if instruction is None:
            instruction = demo.instruction
        elif demo.instruction != instruction:
            raise DemoFileError(f"{task.id}: demonstrations disagree on the instruction ({instruction!r})")
        _write_demo(data.create_group(f"demo_{index}"), demo, frames)
        total += demo.length
    problem = files.scene_problem(task)
    problem_info = {
        # LIBERO's get_problem_info lowercases the problem name (it selects the env class case-insensitively);
        # every LIBERO BDDL declares the robosuite domain.
        "problem_name": problem.problem_name.lower(),
        "domain_name": "robosuite",
        "language_instruction": instruction,
    }
    env_kwargs: dict = {"robots": [ROBOT], "controller": CONTROLLER, "control_freq": CONTROL_HZ}
    if image_size:
        env_kwargs.update(
            camera_names=list(IMAGE_KEYS), camera_heights=image_size, camera_widths=image_size, use_camera_obs=True
        )
        data.attrs["image_orientation"] = IMAGE_ORIENTATION
    env_args = {
        "type": ROBOSUITE_ENV_TYPE,
        "env_name": problem.problem_name,
        "problem_name": problem_info["problem_name"],
        "env_kwargs": env_kwargs,
    }
    data.attrs.update(
        {
            "problem_info": json.dumps(problem_info),
            "env_args": json.dumps(env_args),
            # The BDDL LIBERO builds the task from (a generated file for extended tasks: kept here, not its path).
            "bddl_file_content": files.task_bddl_text(task),
            "num_demos": len(data),
            "total": total,
            "langgap_task_id": task.id,
            "langgap_catalog": collection["catalog"],
            "langgap_version": code_version(),
            "langgap_collection": json.dumps(collection, sort_keys=True),
            "physics": json.dumps(stack.physics_stack(), sort_keys=True),
        }
    )


def _write_demo(group, demo: Demo, frames: dict[str, np.ndarray]) -> None:
    done = np.zeros(demo.length, dtype=np.uint8)
    done[-1] = 1  # a kept demonstration reaches the goal at its last step (verify-demos checks it)
    group.create_dataset("actions", data=demo.actions).attrs["description"] = (
        "executed actions (with the collection's execution noise): what a replay applies"
    )
    group.create_dataset("labels", data=demo.labels).attrs["description"] = (
        "the oracle's clean commands: the training targets (DART)"
    )
    group.create_dataset("states", data=demo.states)
    group.create_dataset("robot_states", data=demo.robot_states)
    group.create_dataset("rewards", data=done)
    group.create_dataset("dones", data=done)
    group.create_dataset("body_pos", data=demo.body_pos)
    group.create_dataset("body_quat", data=demo.body_quat)
    group.attrs.update(
        {
            "num_samples": demo.length,
            "seed": demo.seed,
            "nearest_init_distance": demo.nearest_init_distance,
            "scene_hash": demo.scene_hash,
            "init_state": demo.states[0],
        }
    )
    obs = group.create_group("obs")
    for key, value in sorted(demo.privileged.items()):
        name = obs_name(key)
        if name in obs:
            raise DemoFileError(f"{demo.task_id}: privileged keys collide as {name!r} in HDF5")
        obs.create_dataset(name, data=value).attrs["langgap_key"] = key
    for camera, key in IMAGE_KEYS.items():
        if camera in frames:
            image = frames[camera]
            # One frame per chunk: a training loader reads frames at random.
            dataset = obs.create_dataset(
                key, data=image, chunks=(1, *image.shape[1:]), compression="gzip", compression_opts=GZIP_LEVEL
            )
            dataset.attrs["camera"] = camera
            dataset.attrs["orientation"] = IMAGE_ORIENTATION
