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
    """One node's executive counters, cumulative over the run (``ExecStats``)."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("refused",)

    cycle_slips: dict[str, int] = Field(description="runs over budget, by rate group")
    max_exec_ms: dict[str, float] = Field(description="longest run, ms (wall), by rate group")
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
