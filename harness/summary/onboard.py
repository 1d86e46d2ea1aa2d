"""summary.json's ``onboard_fdir`` section: what the agent-level FDIR onboard did
(fsw/apps/fdir.py), present when the scenario turns it on (``[onboard_fdir] enabled``); from a
run's archive: every event of it, its counts, and for each injected fault what the ground
declared (from the run's scores) and what its spacecraft did after the onset, with the
times."""

from __future__ import annotations

from collections.abc import Sequence

from pydantic import Field

from harness.archive.reader import RunArchive
from harness.summary.archive_info import BUS_HEADER
from harness.summary.records import SummaryRecord
from harness.summary.scoring import Scores
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import OnboardFdirEvent
from interfaces.contracts.scenario import Fault


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


def _first(events: Sequence[OnboardFdirEvent], spacecraft: int, kind: str,
           after_s: float | None, classed: bool = False) -> OnboardFdirEvent | None:
    """The first event ``kind`` of ``spacecraft`` at or after ``after_s`` (with a class, if
    ``classed``); None when there is none, or no time to start from."""
    if after_s is None:
        return None
    return next((e for e in events if e.spacecraft == spacecraft and e.event == kind
                 and e.t_sim >= after_s and (e.fault_class is not None or not classed)), None)


def fault_record(fault: Fault, events: Sequence[OnboardFdirEvent],
                 scores: Scores | None, index: int) -> OnboardFaultRecord:
    """Fault ``index`` of the scenario: the ground's detection and class (``scores``); its
    spacecraft's first classed report received after the onset and the sequence it started
    (in the same step, the app's sequences follow their report's event); its first watchpoint
    trip after the onset and the sequence that started."""
    score = scores.per_fault[index] if scores and index < len(scores.per_fault) else None
    report = _first(events, fault.spacecraft, "report", fault.start_s, classed=True)
    action = _first(events, fault.spacecraft, "sequence", report.t_sim if report else None,
                    classed=True)
    trip = _first(events, fault.spacecraft, "trip", fault.start_s)
    after_trip = _first(events, fault.spacecraft, "sequence", trip.t_sim if trip else None)
    trip_action = after_trip.name if after_trip and trip and after_trip.t_sim == trip.t_sim \
        else None
    lat = score.latency_s if score and score.isolated else None
    ident = score.identification_latency_s if score else None
    return OnboardFaultRecord(
        spacecraft=fault.spacecraft, kind=fault.kind, start_s=fault.start_s,
        detected_s=None if lat is None else fault.start_s + lat,
        identified_class=score.identified_class if score else None,
        identified_s=None if ident is None else fault.start_s + ident,
        report_received_s=report.t_sim if report else None,
        action=action.name if action else None, action_s=action.t_sim if action else None,
        trip=trip.name if trip else None, trip_s=trip.t_sim if trip else None,
        trip_action=trip_action)


def onboard_summary(archive: RunArchive, mission: str, faults: Sequence[Fault],
                    scores: Scores | None) -> OnboardFdirSummary:
    """The ``onboard_fdir`` section of a run with the onboard FDIR on."""
    events = sorted(archive.of(cat.FDIR_EVENT, mission), key=lambda e: (e.t_sim, e.spacecraft))

    def count(kind: str) -> int:
        return sum(e.event == kind for e in events)

    return OnboardFdirSummary(
        trips=count("trip"), actions=count("sequence"), reports=count("report"),
        recoveries=count("recovered"),
        per_fault=[fault_record(f, events, scores, k) for k, f in enumerate(faults)],
        events=[OnboardEventRecord.model_validate(e.model_dump(exclude=BUS_HEADER))
                for e in events])
