"""The oracle's ceiling beside every rate, from the catalog's recorded feasibility verdicts."""

from __future__ import annotations

import dataclasses

from langgap.catalog.task import GateResult
from langgap.catalog.verdicts import read_verdicts, record_verdicts
from langgap.report import load_runs, summarize
from langgap.report.formats import FORMATS
from tests.unit.reports import episode, write_run

DRAWER = "spatial/s2/open-cabinet-bottom-drawer"  # rejected by the gate: the oracle never opened it
BOWL = "spatial/s2/black-bowl-1-on-plate"


def test_the_oracle_on_exactly_the_init_states_a_run_used():
    gate = GateResult(episodes=20, successes=17, feasible=False, inits=20, failed_inits=[3, 4, 15])
    assert gate.oracle_on(range(5)) == (3, 5)
    assert gate.oracle_on([15, 16, 30]) == (1, 2)  # init state 30 was not gated
    assert gate.oracle_on([30, 31]) == (17, 20)  # none gated: the gate's whole result
    older = GateResult(episodes=10, successes=9, feasible=True)  # recorded without per-init results
    assert older.oracle_on(range(3)) == (9, 10)
    assert gate.capped and not GateResult(20, 20, True).capped
    assert GateResult(20, 20, True, certificate="no grasp reachable").capped


def test_re_gating_keeps_a_certificate(tmp_path):
    registry = tmp_path / "mine.yaml"
    record_verdicts(registry, {DRAWER: GateResult(10, 0, False, certificate="unreachable handle")}, {})
    record_verdicts(registry, {DRAWER: GateResult(50, 0, False, inits=50, failed_inits=range(50))}, {})
    (verdict,) = read_verdicts(registry).values()
    assert (verdict.episodes, verdict.certificate, len(verdict.failed_inits)) == (50, "unreachable handle", 50)


def _run(tmp_path, name: str, successes: dict[str, int]):
    records = []
    for task, wins in successes.items():
        for init in range(4):
            record = episode("spatial/s0/ramekin-on-plate", init, success=init < wins)
            records.append(dataclasses.replace(record, task_id=task, suite="libero_spatial", catalog="langgap99"))
    return write_run(tmp_path / name, name, records, catalog="langgap99")


def test_reports_show_the_ceiling_and_mark_tasks_that_cap_it(tmp_path):
    (run,) = summarize(load_runs([_run(tmp_path, "vla", {DRAWER: 0, BOWL: 2})])).runs
    rates = {t.rate.group: t.rate for t in run.tasks}
    assert (rates[BOWL].oracle_rate, rates[BOWL].relative) == (1.0, 0.5)
    assert rates[DRAWER].oracle_rate == 0.0 and rates[DRAWER].relative is None
    assert run.capped == {DRAWER: "certified infeasible"}  # langgap certify recorded its certificate
    # both tasks are extended; the oracle on the run's init states 0-3 of each (the gate kept per-init results)
    extended = run.source("extended")
    assert (extended.oracle_successes, extended.oracle_episodes) == (4, 8)
    markdown = FORMATS["md"](summarize(load_runs([tmp_path / "vla"])), None)
    assert f"| {DRAWER} ⚠ |" in markdown and f"⚠ {DRAWER} (certified infeasible)" in markdown
    assert f"| {BOWL} |" in markdown


def test_a_task_is_capped_by_a_low_oracle_or_a_certificate():
    from langgap.report.stats import Rate
    from langgap.report.summary import capped_because

    low = Rate("t", 20, 5, 0, 1, oracle_successes=18, oracle_episodes=20)
    assert capped_because(low, GateResult(20, 18, True)) == "oracle 18/20"
    fine = Rate("t", 20, 5, 0, 1, oracle_successes=19, oracle_episodes=20)
    assert capped_because(fine, GateResult(20, 19, True)) is None
    assert capped_because(fine, GateResult(20, 19, True, certificate="…")) == "certified infeasible"
    assert capped_because(fine, None) is None


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
