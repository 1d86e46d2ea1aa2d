"""The verdict at a glance (harness/summary/verdict.py) of summaries built here: the
detections are scored by the scorer (harness/summary/scoring.py), and the verdict must say
what was declared, on whom, when, by which test and class, what was missed, and the false
alarms by name."""

from __future__ import annotations

from harness.summary import Detection, RunSummary
from harness.summary.scoring import Alarm, Judged, score
from harness.summary.verdict import verdict
from interfaces.contracts.scenario import Fault

PERIOD_S = 10.0
CAMERA = Fault(spacecraft=2, kind="camera_degradation", start_s=310.0, magnitude=0.5)
THRUSTER = Fault(spacecraft=4, kind="thruster_bias", start_s=600.0, magnitude=0.01)


def _detection(sc: int, t: float, cls: str | None, **kw: object) -> Detection:
    return Detection.model_validate({"spacecraft": sc, "time_s": t, "class": cls,
                                     "direction": None, "metric": 1.0, "threshold": 0.5, **kw})


def _summary(faults: list[Fault], detections: list[Detection]) -> RunSummary:
    """A run of 4 observers over 900 s, its detections scored as the builder scores them."""
    judged = [Judged(sc, t, t + PERIOD_S) for sc in range(1, 5)
              for t in range(0, 900, int(PERIOD_S))]
    alarms = [Alarm(d.spacecraft, d.time_s, d.fault_class, d.declared_s) for d in detections]
    summary = RunSummary(scenario="t", seed=1, status="completed", error=None,
                         injected_faults=faults)
    summary.detections = detections
    summary.scores = score(faults, alarms, judged, grace_s=PERIOD_S)
    return summary


def test_a_declared_fault_is_named_with_its_test_class_and_latency() -> None:
    nis = _detection(2, 312.4, None, detector="sequential", test="nis_scan")
    named = _detection(2, 320.0, "camera", test="information")
    v = verdict(_summary([CAMERA], [nis, named]))
    line = v.line()
    assert line.startswith("1 of 1 faults declared: sc2 at t=312.4 s (+2.4 s, NIS scan")
    assert "camera; injected camera_degradation at 310.0 s" in line
    # 4 x 90 windows, less sc2's 59 from 310 s on (the fault has no end)
    assert line.endswith("0 false alarms in 301 nominal windows.")
    assert v.faults[0].alarm == nis


def test_a_missed_fault_is_named_as_not_declared() -> None:
    v = verdict(_summary([CAMERA, THRUSTER], [_detection(2, 320.0, "actuator")]))
    line = v.line()
    assert line.startswith("1 of 2 faults declared: ")
    assert "sc2 at t=320.0 s (+10.0 s, information test (Eq. 9), actuator, expected camera;" \
        in line
    assert "sc4 thruster_bias at 600.0 s: not declared" in line


def test_a_false_alarm_is_named_with_its_spacecraft_class_and_time() -> None:
    v = verdict(_summary([], [_detection(3, 150.0, "actuator")]))
    assert v.line() == ("no fault injected. 1 false alarm in 360 nominal windows: sc3 actuator "
                        "at t=150.0 s (information test (Eq. 9)).")
    assert v.false_alarm_count == 1 and v.false_alarms[0].spacecraft == 3


def test_a_nominal_run_says_nothing_was_injected_or_declared() -> None:
    assert verdict(_summary([], [])).line() == \
        "no fault injected. 0 false alarms in 360 nominal windows."


def test_a_summary_without_scores_says_why_there_is_no_verdict() -> None:
    summary = RunSummary(scenario="t", seed=1, status="failed", error="boom",
                         injected_faults=[CAMERA], archive_error="run.mcap: truncated")
    assert verdict(summary).line() == "no FDIR verdict: run.mcap: truncated"


def test_the_markdown_opens_on_the_verdict_with_a_row_per_fault_and_false_alarm() -> None:
    v = verdict(_summary([CAMERA, THRUSTER], [_detection(2, 320.0, "camera"),
                                              _detection(1, 100.0, None)]))
    md = v.markdown()
    assert md[0] == "## Verdict" and md[2] == f"**{v.line()}**"
    rows = [ln for ln in md if ln.startswith("| sc")]
    assert rows[0].startswith("| sc2 camera_degradation | 310.0 | yes | sc2 | information test")
    assert rows[1].startswith("| sc4 thruster_bias | 600.0 | **no** |")
    assert rows[2].startswith("| sc1 | 100.0 | information test (Eq. 9) | unidentified |")
