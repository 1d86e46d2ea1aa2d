"""The onboard FDIR judged on a campaign (harness/campaign/onboard_study.py), on summaries
whose answer is known: a sequence started in the report's own tick counts as prompt and one a
tick late does not; a trip before the ground's detection is counted; nominal trips are summed;
the final H is compared run by run."""

from __future__ import annotations

from pathlib import Path

from harness.campaign.onboard_study import write_onboard_report
from harness.summary import (
    CoverageSummary,
    FaultScore,
    OnboardFaultRecord,
    OnboardFdirSummary,
    RunSummary,
    Scores,
)
from interfaces.contracts.scenario import Fault

FAULT = Fault(spacecraft=2, kind="pointing_actuator", start_s=100.0, magnitude=5.0)


def _summary(h_final: float, fault: Fault | None, onboard: OnboardFdirSummary | None
             ) -> RunSummary:
    faults = [fault] if fault else []
    per_fault = [FaultScore(spacecraft=2, kind=fault.kind, start_s=100.0, detected=True,
                            isolated=True, latency_s=20.0, identified_class="actuator",
                            expected_class="actuator", identified_correctly=True,
                            identification_latency_s=20.0)] if fault else []
    s = RunSummary(scenario="p", seed=1, status="completed", error=None, injected_faults=faults)
    s.scores = Scores(per_fault=per_fault, false_alarms=0, nominal_cycles=10,
                      false_alarm_rate=0.0, false_alarms_per_hour=0.0)
    s.coverage = CoverageSummary(H_initial=1.0, H_final=h_final, fraction_observed=0.9,
                                 H_i_final={}, H_reduction_fraction=1.0 - h_final,
                                 assignment_decisions=[])
    s.onboard_fdir = onboard
    return s


def _onboard(action_s: float | None, trips: int = 1) -> OnboardFdirSummary:
    record = OnboardFaultRecord(
        spacecraft=2, kind="pointing_actuator", start_s=100.0, detected_s=120.0,
        identified_class="actuator", identified_s=120.0, report_received_s=123.1,
        action="safe_hold" if action_s else None, action_s=action_s, trip="pointing_deg",
        trip_s=108.0, trip_action="request_plan")
    return OnboardFdirSummary(trips=trips, actions=2, reports=1, recoveries=0,
                              per_fault=[record], events=[])


def _write(root: Path, rid: str, s: RunSummary) -> None:
    (root / "runs" / rid).mkdir(parents=True)
    s.write(root / "runs" / rid / "summary.json")


def test_the_report_counts_prompt_actions_early_trips_nominal_trips_and_h(tmp_path: Path) -> None:
    on, off = tmp_path / "on", tmp_path / "off"
    _write(on, "f-0", _summary(0.40, FAULT, _onboard(123.1)))   # in the report's tick
    _write(on, "f-1", _summary(0.44, FAULT, _onboard(123.3)))   # two ticks late
    _write(on, "n-0", _summary(0.30, None, OnboardFdirSummary(
        trips=2, actions=1, reports=0, recoveries=0, per_fault=[], events=[])))
    for rid, h in (("f-0", 0.42), ("f-1", 0.42), ("n-0", 0.30)):
        _write(off, rid, _summary(h, FAULT if rid.startswith("f") else None, None))
    text = write_onboard_report(on, off).read_text()
    assert "1 nominal runs: **2 watchpoint trips, 1 sequences started**" in text
    assert "| pointing_actuator | 2 | 2 | 1 of 2 acted on | 2 | 2 / 2 | 2 / 2 |" in text
    assert "| actuator | pointing_actuator | 2 | 0.4200 | 0.4200 | +0.0000 (-0.0200 / +0.0200) |" \
        in text
