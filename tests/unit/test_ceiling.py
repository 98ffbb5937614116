"""The oracle's ceiling beside every rate, from the catalog's recorded feasibility verdicts."""

from __future__ import annotations

import dataclasses
import json

import pytest

from langgap.catalog.catalog import registry_path
from langgap.catalog.verdicts import GateResult, read_verdicts, record_verdicts, verdicts_path
from langgap.errors import CatalogError
from langgap.report import load_runs, summarize
from langgap.report.formats import FORMATS
from langgap.report.tables import STACK_NOTE
from tests.support.reports import episode, write_run

DRAWER = "spatial/s2/open-cabinet-bottom-drawer"
BOWL = "spatial/s2/black-bowl-1-on-plate"


def test_the_oracle_on_exactly_the_init_states_a_run_used():
    gate = GateResult(episodes=20, successes=17, feasible=False, inits=20, failed_inits=[3, 4, 15])
    assert gate.oracle_on(range(5)) == (3, 5)
    assert gate.oracle_on([15, 16, 30]) == (1, 2)  # init state 30 was not gated
    assert gate.oracle_on([30, 31]) == (17, 20)  # none gated: the gate's whole result
    older = GateResult(episodes=10, successes=9, feasible=True)  # recorded without per-init results
    assert older.oracle_on(range(3)) == (9, 10)
    assert gate.capped and not GateResult(20, 20, True).capped
    assert GateResult(20, 20, False, proof="out of reach").capped


def test_a_certificate_written_by_an_older_langgap_is_dropped_on_reading(tmp_path):
    registry = tmp_path / "mine.yaml"
    record_verdicts(registry, {DRAWER: GateResult(10, 0, False, inits=10, failed_inits=range(10))}, {})
    path = verdicts_path(registry)
    data = json.loads(path.read_text())
    data["tasks"][DRAWER]["certificate"] = "Reachability on init state 0: of 930 gripper poses ..."
    path.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
    (verdict,) = read_verdicts(registry).values()
    assert (verdict.episodes, verdict.proof, verdict.feasible) == (10, "", False)  # no proof: still unproven
    assert "certificate" not in {f.name for f in dataclasses.fields(GateResult)}
    record_verdicts(registry, {BOWL: GateResult(5, 5, True)}, {})  # rewriting the file leaves it out
    assert "certificate" not in json.loads(path.read_text())["tasks"][DRAWER]


def test_a_verdict_is_not_both_feasible_and_proven_impossible():
    with pytest.raises(CatalogError, match="proof"):
        GateResult(5, 5, True, proof="out of reach")


def _run(tmp_path, name: str, successes: dict[str, int], verdicts: dict[str, GateResult]):
    """A run of 4 init states per task, on a copy of langgap99 whose gate recorded `verdicts`."""
    registry = tmp_path / "langgap99.yaml"
    if not registry.exists():
        registry.write_text(registry_path("langgap99").read_text())
    record_verdicts(registry, verdicts, {})
    records = []
    for task, wins in successes.items():
        for init in range(4):
            record = episode("spatial/s0/ramekin-on-plate", init, success=init < wins)
            records.append(
                dataclasses.replace(record, task_id=task, suite="libero_spatial", catalog="langgap99", physics=STACK)
            )
    return write_run(tmp_path / name, name, records, catalog=str(registry))


STACK = {"mujoco": "3.2.3", "robosuite": "1.4.1", "start": "fresh-env"}  # the runs' episodes' physics
UNPROVEN = GateResult(
    50, 17, False, reason="oracle 17/50", inits=50, failed_inits=[i for i in range(50) if i % 3], physics=STACK
)
ACCEPTED = GateResult(
    50, 50, True, inits=50, failed_inits=[], made_by="oracle, langgap 0.1.0, exact stepping", physics=STACK
)


def test_reports_show_the_ceiling_and_mark_a_task_the_oracle_fails_as_unproven(tmp_path):
    (run,) = summarize(
        load_runs([_run(tmp_path, "vla", {DRAWER: 0, BOWL: 2}, {DRAWER: UNPROVEN, BOWL: ACCEPTED})])
    ).runs
    rates = {t.rate.group: t.rate for t in run.tasks}
    assert (rates[BOWL].oracle_rate, rates[BOWL].relative) == (1.0, 0.5)
    assert rates[DRAWER].oracle_rate == 0.5 and rates[DRAWER].relative == 0.0  # init states 0 and 3 of 0-3
    assert run.capped == {DRAWER: "unproven: the oracle does not do it (2/4); no proof that a policy cannot"}
    # both tasks are extended; the oracle on the run's init states 0-3 of each (the gate kept per-init results)
    extended = run.source("extended")
    assert (extended.oracle_successes, extended.oracle_episodes) == (6, 8)
    markdown = FORMATS["md"](summarize(load_runs([tmp_path / "vla"])), None)
    assert f"| {DRAWER} ⚠ |" in markdown and f"⚠ {DRAWER} (unproven: the oracle does not do it (2/4);" in markdown
    assert f"| {BOWL} |" in markdown
    # the oracle failing a task shows nothing about other policies: neither the header nor the notes say so
    assert "infeasible (proof)" not in markdown and "certified" not in markdown
    assert "caps what any policy can show" not in markdown
    assert "⚠ marks a task the oracle does on fewer than 95 % of these init states" in markdown


def test_the_warning_legend_is_shown_with_a_warning_only_plain_and_with_both_rates(tmp_path):
    from langgap.report.tables import CAPPED_NOTE, notes, selection_text

    fine = load_runs([_run(tmp_path, "fine", {BOWL: 2}, {BOWL: ACCEPTED})])
    markdown = FORMATS["md"](summarize(fine), None)
    assert "⚠ marks" not in markdown and "--tasks feasible (the default)" in markdown
    (tmp_path / "other").mkdir()  # catalogs are cached by path: another registry
    warned = load_runs([_run(tmp_path / "other", "warned", {DRAWER: 0, BOWL: 2}, {DRAWER: UNPROVEN, BOWL: ACCEPTED})])
    summary = summarize(warned)
    assert CAPPED_NOTE in FORMATS["md"](summary, None) and CAPPED_NOTE in notes(summary, None)
    # which rate is which: ⚠ below the ceiling target on the run's init states; the gate admits at its own rate
    assert "⚠ marks a task the oracle does on fewer than 95 % of these init states" in CAPPED_NOTE
    assert "the oracle, with searched demonstrations, does at least 90 % of its init states" in CAPPED_NOTE
    # the terminal shows the notes and the header as they are: no Markdown code quotes
    (run,) = summary.runs
    run.spec["selection"] = "spatial/s2/*"
    assert not [note for note in notes(summary, None) if "`" in note] and "`" not in selection_text(run)
    assert "tasks: 'spatial/s2/*'; ⚠" in selection_text(run)


def test_reports_mark_a_ceiling_whose_verdict_was_made_on_another_stack(tmp_path):
    older = dataclasses.replace(UNPROVEN, physics=STACK | {"robosuite": "1.4.0", "start": "cleared-warmstart"})
    runs = load_runs([_run(tmp_path, "vla", {DRAWER: 0, BOWL: 2}, {DRAWER: older, BOWL: ACCEPTED})])
    (run,) = summarize(runs).runs
    assert run.other_stack == {DRAWER: ["robosuite 1.4.0 (not 1.4.1)", "start cleared-warmstart (not fresh-env)"]}
    markdown = FORMATS["md"](summarize(runs), None)
    assert f"| {DRAWER} ⚠ ≠ |" in markdown and f"| {BOWL} |" in markdown and STACK_NOTE in markdown
    # The same stack: no mark, no note.
    (tmp_path / "same").mkdir()
    same_run = _run(tmp_path / "same", "vla", {DRAWER: 0, BOWL: 2}, {DRAWER: UNPROVEN, BOWL: ACCEPTED})
    same = FORMATS["md"](summarize(load_runs([same_run])), None)
    assert f"| {DRAWER} ⚠ |" in same and "≠" not in same


def test_reports_mark_a_task_with_a_proof_infeasible(tmp_path):
    proven = GateResult(50, 0, False, reason="oracle 0/50", inits=50, failed_inits=range(50), proof="Out of reach")
    runs = load_runs([_run(tmp_path, "vla", {DRAWER: 0, BOWL: 2}, {DRAWER: proven, BOWL: ACCEPTED})])
    (run,) = summarize(runs).runs
    assert run.capped == {DRAWER: "infeasible: a proof that no policy can do it"}
    markdown = FORMATS["md"](summarize(runs), None)
    assert f"⚠ {DRAWER} (infeasible: a proof that no policy can do it)" in markdown
    assert "unproven: the oracle" not in markdown


def test_reports_mark_a_task_whose_starts_do_not_come_to_rest_unsettled(tmp_path):
    """The oracle did it on every init state; the gate rejected it for its starts: ⚠, as unsettled, not unproven."""
    restless = dataclasses.replace(ACCEPTED, feasible=False, reason="scene settles", made_by="")
    runs = load_runs([_run(tmp_path, "vla", {DRAWER: 0, BOWL: 2}, {DRAWER: restless, BOWL: ACCEPTED})])
    (run,) = summarize(runs).runs
    assert run.capped == {DRAWER: "unsettled: its starts do not come to rest (the oracle did it 4/4)"}
    markdown = FORMATS["md"](summarize(runs), None)
    assert f"| {DRAWER} ⚠ |" in markdown and f"⚠ {DRAWER} (unsettled: its starts do not come to rest" in markdown
    assert "unproven" not in markdown.split("\n\n")[1]  # the run's header line
    assert json.loads(FORMATS["json"](summarize(runs), None))["runs"][0]["capped_tasks"] == run.capped


def test_a_task_is_marked_by_a_low_oracle_by_its_verdict_or_by_a_proof_as_infeasible():
    from langgap.report.stats import Rate
    from langgap.report.summary import capped_because

    low = Rate("t", 20, 5, 0, 1, oracle_successes=18, oracle_episodes=20)
    unproven = capped_because(low, GateResult(20, 18, False, reason="oracle 18/20"))
    assert unproven == "unproven: the oracle does not do it (18/20); no proof that a policy cannot"
    assert "infeasible" not in unproven and "certified" not in unproven
    # The gate admitted it (at 90 %): doable, yet the oracle is below the ceiling target on these init states.
    admitted = capped_because(low, GateResult(20, 18, True))
    assert admitted == "doable, but the oracle does only 18/20 of these init states"
    fine = Rate("t", 20, 5, 0, 1, oracle_successes=19, oracle_episodes=20)
    assert capped_because(fine, GateResult(20, 19, True)) is None
    assert capped_because(fine, GateResult(20, 19, False, proof="…")) == "infeasible: a proof that no policy can do it"
    assert capped_because(fine, None) is None
    searched = GateResult(20, 3, True, demonstration="demos/drawer.npz")
    shown = capped_because(Rate("t", 20, 5, 0, 1, oracle_successes=3, oracle_episodes=20), searched)
    assert shown == "doable by a searched demonstration; the oracle does 3/20 of these init states"


def _record_many(registry: str, worker: int) -> None:
    for i in range(25):
        record_verdicts(registry, {f"spatial/s{worker}/task-{i}": GateResult(5, 5, True)}, {})


def test_concurrent_recordings_lose_no_verdict(tmp_path):
    import multiprocessing

    registry = str(tmp_path / "mine.yaml")
    workers = [multiprocessing.get_context("fork").Process(target=_record_many, args=(registry, w)) for w in range(4)]
    for process in workers:
        process.start()
    for process in workers:
        process.join()
    assert len(read_verdicts(registry)) == 4 * 25
