"""The BLAS kernel is pinned before numpy loads, recorded with the physics stack, and compared only where known."""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from pathlib import Path

import pytest

from langgap.blas import PINNED_CORE, _cpu_flags
from langgap.stack import stack_differences

ROOT = Path(__file__).resolve().parents[2]
PINNABLE = platform.machine().lower() in ("x86_64", "amd64") and {"avx2", "fma"} <= _cpu_flags()
needs_pinnable = pytest.mark.skipif(not PINNABLE, reason="the kernel is pinned only on x86-64 with AVX2 and FMA")


def _kernel(code: str, **env: str) -> list[str]:
    """What a fresh interpreter running `code` prints: OPENBLAS_CORETYPE as it left it, and `blas_core()`."""
    clean = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"} | env
    code += "; import os; from langgap.blas import blas_core; print(os.environ.get('OPENBLAS_CORETYPE'), blas_core())"
    result = subprocess.run([sys.executable, "-c", code], env=clean, cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return result.stdout.split()


@needs_pinnable
def test_importing_langgap_first_pins_the_kernel_numpy_then_runs_on():
    assert _kernel("import langgap, numpy") == [PINNED_CORE, PINNED_CORE]


@needs_pinnable
def test_numpy_loaded_first_keeps_its_own_kernel_and_a_user_s_choice_is_kept():
    assert _kernel("import numpy, langgap")[0] == "None"
    assert _kernel("import langgap, numpy", OPENBLAS_CORETYPE="Sandybridge") == ["Sandybridge", "Sandybridge"]


def test_the_kernel_is_a_difference_only_where_both_stacks_record_it():
    made_on = {"mujoco": "3.2.3", "blas": "SkylakeX"}
    assert stack_differences(made_on, {"mujoco": "3.2.3", "blas": PINNED_CORE}) == [
        f"blas SkylakeX (not {PINNED_CORE})"
    ]
    assert stack_differences({"mujoco": "3.2.3"}, {"mujoco": "3.2.3", "blas": PINNED_CORE}) == []
    assert stack_differences(made_on, {"mujoco": "3.2.3"}) == []
    # the other entries still count when missing on one side
    assert stack_differences({"mujoco": "3.2.3"}, {"mujoco": "3.2.3", "numba": "0.68.1"}) == ["numba none (not 0.68.1)"]


def test_a_run_stored_before_the_kernel_was_recorded_resumes_and_one_on_another_kernel_does_not():
    from langgap.engine.spec import spec_differences

    stored = {"policy": "noop", "physics": {"mujoco": "3.2.3"}}
    assert spec_differences(stored, {"policy": "noop", "physics": {"mujoco": "3.2.3", "blas": PINNED_CORE}}) == []
    other = {"policy": "noop", "physics": {"mujoco": "3.2.3", "blas": "SkylakeX"}}
    assert spec_differences(other, {"policy": "noop", "physics": {"mujoco": "3.2.3", "blas": PINNED_CORE}}) == [
        "physics"
    ]
    assert spec_differences({"physics": {"mujoco": "3.2.3"}}, {"physics": {"mujoco": "3.3.0"}}) == ["physics"]
