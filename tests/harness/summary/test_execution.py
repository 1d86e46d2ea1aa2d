"""The executives' section of summary.json and its notes in report.md
(harness/summary/execution.py): each group's budget kept, every slip named with its node,
group, count and longest run against the budget; none said so."""

from __future__ import annotations

from harness.summary.execution import ExecRecord, cycle_slip_notes, exec_record
from interfaces.contracts.messages import ExecStats, GroupStats


def _stats(node: str, high_slips: int, high_max_ms: float) -> ExecStats:
    return ExecStats(sender=node, t_sim=10.0, node=node, groups={
        "high": GroupStats(runs=99, cycle_slips=high_slips, max_exec_ms=high_max_ms,
                           budget_ms=100.0),
        "mid": GroupStats(runs=9, cycle_slips=0, max_exec_ms=12.0, budget_ms=1000.0)})


def test_a_nominal_run_says_there_were_no_slips() -> None:
    notes = cycle_slip_notes({n: exec_record(_stats(n, 0, 40.0)) for n in ("sc1", "ground")})
    assert notes[0].endswith("No cycle slips.") and "CPU time" in notes[0]
    assert cycle_slip_notes(None)[0].endswith("No cycle slips.")


def test_each_slip_is_named_against_its_budget() -> None:
    execs = {"sc1": exec_record(_stats("sc1", 0, 40.0)),
             "sc2": exec_record(_stats("sc2", 3, 325.9))}
    assert execs["sc2"].budget_ms == {"high": 100.0, "mid": 1000.0}
    notes = cycle_slip_notes(execs)
    listed = [line for line in notes if line.startswith("- ")]
    assert listed == ["- sc2, high group: 3 cycle slips, the longest 325.9 ms of CPU over its "
                      "100 ms budget."]
    assert "logged by its node" in notes[0]


def test_an_older_summary_without_budgets_still_names_its_slips() -> None:
    old = ExecRecord.model_validate({"cycle_slips": {"high": 1}, "max_exec_ms": {"high": 130.0},
                                     "app_errors": 0, "invalid_dropped": 0,
                                     "barrier_timeouts": 0})
    assert cycle_slip_notes({"sc1": old})[2] == ("- sc1, high group: 1 cycle slip, the longest "
                                                 "130.0 ms of CPU.")
