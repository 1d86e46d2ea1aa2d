"""``onboard_fdir``: what the agent-level FDIR onboard did (fsw/apps/fdir.py), present when the
scenario turns it on (``[onboard_fdir] enabled``)."""

from __future__ import annotations

from pydantic import Field

from harness.summary.records import SummaryRecord


class OnboardEventRecord(SummaryRecord):
    """An onboard FDIR event (an ``OnboardFdirEvent`` less its bus header)."""

    t_sim: float = Field(description="sim s")
    spacecraft: int = Field(ge=1)
    event: str = Field(description="trip, clear, report, sequence, recovered, plan_request")
    name: str = Field(description="the watchpoint, sequence or class")
    value: float | None = Field(description="a trip's or clear's value (the watchpoint's unit)")
    limit: float | None = Field(description="its limit, same unit")
    fault_class: str | None = Field(description="the class a report or sequence acts on")
    detail: str


class OnboardFaultRecord(SummaryRecord):
    """One injected fault, what the ground declared and what its spacecraft did, with the
    times (sim s; null: never)."""

    spacecraft: int = Field(ge=0)
    kind: str
    start_s: float
    detected_s: float | None = Field(description="the ground's first isolating alarm")
    identified_class: str | None = Field(description="the ground's class")
    identified_s: float | None
    report_received_s: float | None = Field(
        description="the first ground report naming the spacecraft with a class, as it "
                    "reached it (after the onset)")
    action: str | None = Field(description="the first stored sequence that report started")
    action_s: float | None
    trip: str | None = Field(description="the first watchpoint tripped after the onset")
    trip_s: float | None
    trip_action: str | None = Field(description="the sequence that trip started (null: none)")


class OnboardFdirSummary(SummaryRecord):
    """Every onboard FDIR event, the counts, and per injected fault its onboard story."""

    trips: int = Field(ge=0, description="watchpoint trips, all spacecraft")
    actions: int = Field(ge=0, description="stored sequences started (none counted for 'none')")
    reports: int = Field(ge=0, description="ground reports received naming their spacecraft")
    recoveries: int = Field(ge=0, description="safe holds ended by a newer assignment")
    per_fault: list[OnboardFaultRecord]
    events: list[OnboardEventRecord]
