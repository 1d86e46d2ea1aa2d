"""Scoring (harness/summary/scoring.py) on constructed alarm sequences."""

from __future__ import annotations

import pytest

from harness.summary.scoring import Alarm, Judged, score
from interfaces.contracts.scenario import Fault

FAULTS = [Fault(spacecraft=2, kind="camera_degradation", start_s=100.0, magnitude=0.5),
          Fault(spacecraft=4, kind="link_loss", start_s=300.0, end_s=400.0)]


def _windows(n_sc: int, t_end: float, period: float) -> list[Judged]:
    return [Judged(sc, t, t + period) for sc in range(1, n_sc + 1)
            for t in range(0, int(t_end), int(period))]


def test_detection_isolation_latency_and_class() -> None:
    alarms = [Alarm(3, 150.0, "actuator"),   # during fault 1 but on another spacecraft
              Alarm(2, 250.0, "camera"),     # the faulty one, right class
              Alarm(4, 500.0, "link"),       # after fault 2 ended + grace: a false alarm
              Alarm(1, 50.0, None)]          # before any fault: a false alarm
    s = score(FAULTS, alarms, _windows(4, 600.0, 50.0), grace_s=50.0)
    f1, f2 = s.per_fault
    assert (f1.detected, f1.isolated, f1.latency_s, f1.identified_class,
            f1.identified_correctly) == (True, True, 150.0, "camera", True)
    assert (f2.detected, f2.isolated, f2.latency_s) == (False, False, None)
    assert f2.expected_class == "link"
    # false alarms: sc3 at 150 (sc3 healthy), sc4 at 500, sc1 at 50
    assert s.false_alarms == 3
    # nominal windows: all but those overlapping a fault: sc2's from [100, 150) on (10) and
    # sc4's [300, 350) and [350, 400)
    faulty_windows = 10 + 2
    assert s.nominal_cycles == 4 * 12 - faulty_windows
    assert s.false_alarm_rate == pytest.approx(3 / (48 - faulty_windows))
    assert s.false_alarms_per_hour == pytest.approx(3 / ((48 - faulty_windows) * 50 / 3600))


def test_detected_but_not_isolated_uses_the_first_alarm() -> None:
    s = score(FAULTS[:1], [Alarm(1, 180.0, "camera")], [], grace_s=50.0)
    (f,) = s.per_fault
    assert f.detected and not f.isolated and f.latency_s == 80.0
    assert f.identified_class is None and not f.identified_correctly
    assert s.nominal_cycles == 0 and s.false_alarm_rate is None


def test_a_link_alarm_counts_when_it_was_declared() -> None:
    """A cut at 300 s kept the data of the window ending 250 s aboard; the ground declared the
    silence at 380 s, in the pass after it: the fault's detection at 80 s, not a false alarm
    before it.  Any other class counts at its window's end."""
    fault = [Fault(spacecraft=4, kind="link_loss", start_s=300.0)]
    s = score(fault, [Alarm(4, 250.0, "link", declared_s=380.0)], [], grace_s=50.0)
    assert (s.per_fault[0].isolated, s.per_fault[0].latency_s, s.false_alarms) == (True, 80.0, 0)
    s = score(fault, [Alarm(4, 250.0, "actuator", declared_s=380.0)], [], grace_s=50.0)
    assert (s.per_fault[0].isolated, s.false_alarms) == (False, 1)
