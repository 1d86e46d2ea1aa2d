"""summary.json's ``exec`` (each node's executive: cycle slips, app errors, drops) and ``sim``
(the sim's last status: rejected commands, participants lost and back, its pace) sections."""

from __future__ import annotations

from typing import ClassVar

from pydantic import (
    Field,
)

from harness.summary.records import SummaryRecord, given_copies
from interfaces.contracts.messages import (
    ExecStats,
    SimStatus,
)


class ExecRecord(SummaryRecord):
    """One node's executive counters, cumulative over the run (``ExecStats``).  A rate
    group's first run in a process is its start-up, counted in neither ``cycle_slips`` nor
    ``max_exec_ms`` (``interfaces.runtime.executive.judge_run``)."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("refused", "budget_ms")

    cycle_slips: dict[str, int] = Field(
        description="runs that took more CPU time than their budget, by rate group")
    max_exec_ms: dict[str, float] = Field(
        description="longest run, ms of CPU time, by rate group")
    budget_ms: dict[str, float] = Field(
        default_factory=dict, description="a run's budget, ms of CPU time, by rate group")
    app_errors: int = Field(ge=0)
    invalid_dropped: int = Field(ge=0, description="invalid messages dropped")
    refused: int = Field(default=0, ge=0, description="messages refused at admission")
    barrier_timeouts: int = Field(ge=0)


class PaceRecord(SummaryRecord):
    """``sim.pace``: how a ``--realtime`` run was paced (``sim/pacing.py``); the factor it
    achieved is the summary's ``real_time_factor``."""

    ceiling: float = Field(gt=0.0, description="--realtime SPEED, × real time")
    hard_deadline: bool = Field(description="answers waited for only until the next tick")
    late_ticks: dict[str, int] = Field(
        default_factory=dict, description="per node, the ticks its answer came too late for")


class SimRecord(SummaryRecord):
    """``sim``: the sim's last status."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("participants",)

    rejected_commands: int | None = Field(
        description="actuator commands refused (null: no status received)")
    participants: dict[str, list[SimStatus.Event]] = Field(
        default_factory=dict, description="nodes lost from the lockstep and rejoined, by node")
    pace: PaceRecord | None = Field(
        default=None, description="a --realtime run's pacing (absent: lockstep alone)")


def exec_record(m: ExecStats) -> ExecRecord:
    return ExecRecord(cycle_slips={g: s.cycle_slips for g, s in m.groups.items()},
                      max_exec_ms={g: round(s.max_exec_ms, 3) for g, s in m.groups.items()},
                      budget_ms={g: round(s.budget_ms, 3) for g, s in m.groups.items()},
                      app_errors=m.app_errors, invalid_dropped=m.invalid_dropped,
                      refused=m.refused, barrier_timeouts=m.barrier_timeouts)


def sim_record(statuses: list[SimStatus]) -> SimRecord:
    """``sim`` from the sim's last status (none: nothing rejected is known)."""
    if not statuses:
        return SimRecord(rejected_commands=None, participants={})
    last = statuses[-1]
    record = SimRecord(rejected_commands=last.rejected_commands,
                       participants={n: given_copies(ev) for n, ev in last.participants.items()})
    if last.pace_ceiling is not None:
        record.pace = PaceRecord(ceiling=last.pace_ceiling, hard_deadline=last.hard_deadline,
                                 late_ticks=dict(last.late_ticks))
    return record


SLIP_MEANING = ("A cycle slip is a run of a rate group that took more CPU time than its budget "
                "(its period × `sim.cycle_budget_scale`); a group's first run in a process, its "
                "start-up (code loaded on first use), is not counted, and the max exec ms are "
                "the longest runs counted, in ms of CPU time.")


def cycle_slip_notes(execs: dict[str, ExecRecord] | None) -> list[str]:
    """The report's lines under the executives' table: what a cycle slip is, then each
    node's slips by rate group, against the group's budget (none: said so)."""
    slipped = [(node, g, n, e) for node, e in (execs or {}).items()
               for g, n in e.cycle_slips.items() if n]
    if not slipped:
        return [SLIP_MEANING + " No cycle slips.", ""]
    return [SLIP_MEANING + " Each slip is logged by its node with its time, its duration and "
            "the app that took longest (over Zenoh in `logs/`, in one process on the "
            "console):", "", *(_slip_line(node, g, n, e) for node, g, n, e in slipped), ""]


def _slip_line(node: str, group: str, slips: int, e: ExecRecord) -> str:
    budget = e.budget_ms.get(group)
    over = f" over its {budget:.0f} ms budget" if budget else ""
    return (f"- {node}, {group} group: {slips} cycle slip{'s' if slips > 1 else ''}, the "
            f"longest {e.max_exec_ms.get(group, 0.0):.1f} ms of CPU{over}.")
