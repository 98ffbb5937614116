"""Which BLAS kernel numpy runs on, pinned so that the physics is the same on every x86-64 machine.

robosuite's arm controller multiplies small matrices with numpy, and numpy hands them to OpenBLAS, which picks
a kernel for the CPU it finds (`Haswell` on most machines, `SkylakeX` on Intel chips with AVX-512). Kernels sum
in different orders, so the last bits of the controller's torques differ, and an episode replayed open loop on
another kernel reaches its goal a few steps earlier or not at all (a stored demonstration recorded on `SkylakeX`
reached its goal at step 186 instead of 187 on `Haswell`). LangGap therefore asks OpenBLAS for one kernel,
`PINNED_CORE`, wherever the CPU can run it, and records the kernel in use with every result
(`langgap.stack.physics_stack`).

The choice has to be made before numpy is first imported (OpenBLAS reads `OPENBLAS_CORETYPE` when it loads):
`import langgap` does it, and a process that imported numpy first keeps the kernel OpenBLAS chose, which its
results then name. A user's own `OPENBLAS_CORETYPE` is left as it is. This module needs only the standard
library until `blas_core` is called.
"""

from __future__ import annotations

import ctypes
import functools
import glob
import os
import platform
import sys
from pathlib import Path

# AVX2 and FMA: every x86-64 server and laptop CPU of the last decade, and OpenBLAS's own choice on most of them
PINNED_CORE = "Haswell"
_NEEDS = {"avx2", "fma"}
_CORENAME_SYMBOLS = ("scipy_openblas_get_corename64_", "scipy_openblas_get_corename", "openblas_get_corename")


def _cpu_flags() -> set[str]:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    line = next((line for line in text.splitlines() if line.startswith("flags")), "")
    return set(line.partition(":")[2].split())


def pin_blas_core() -> None:
    """Ask OpenBLAS for `PINNED_CORE` in this process and the processes it starts, unless numpy is loaded
    already, the user chose a kernel (`OPENBLAS_CORETYPE`), or the CPU cannot run it (not x86-64 with AVX2
    and FMA, or no /proc/cpuinfo to say so)."""
    if "numpy" in sys.modules or "OPENBLAS_CORETYPE" in os.environ:
        return
    if platform.machine().lower() in ("x86_64", "amd64") and _cpu_flags() >= _NEEDS:
        os.environ["OPENBLAS_CORETYPE"] = PINNED_CORE


@functools.cache
def blas_core() -> str:
    """The BLAS numpy runs on: OpenBLAS's kernel name (`Haswell`, `SkylakeX`, ...), else the library's name
    (`accelerate` on macOS); `unknown` when neither can be read. Read once: OpenBLAS chooses when it loads."""
    import numpy

    blas = numpy.__config__.CONFIG.get("Build Dependencies", {}).get("blas", {}).get("name") or "unknown"
    if "openblas" not in blas:
        return blas
    package = Path(numpy.__file__).parent
    # where numpy's wheels keep their OpenBLAS: numpy.libs/ beside the package (Linux), .dylibs/ inside (macOS)
    libraries = glob.glob(f"{package.parent}/numpy.libs/*openblas*") + glob.glob(f"{package}/.dylibs/*openblas*")
    for library in sorted(libraries):
        handle = ctypes.CDLL(library)
        for symbol in _CORENAME_SYMBOLS:
            corename = getattr(handle, symbol, None)
            if corename is not None:
                corename.restype = ctypes.c_char_p
                return corename().decode()
    return blas
