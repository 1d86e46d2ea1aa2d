"""The FDI window schedule: windows and boundaries by index, times matched to boundaries within
a tolerance (never by float equality), for periods whose multiples are not exact in binary."""

from __future__ import annotations

import pytest

from interfaces.contracts.fdi_schedule import FdiSchedule


@pytest.mark.parametrize("period", [100.0, 2.0, 0.3, 7.0 / 3.0])
def test_boundaries_and_windows_by_index(period: float) -> None:
    s = FdiSchedule(period)
    t = 0.0
    for j in range(1, 200):
        t += period  # accumulated, as a clock would: not exactly j * period
        assert s.boundary_at(t) == j
        assert s.end(j - 1) == s.start(j) == j * period
        assert s.boundary_at(t + 0.01 * period) is None


def test_a_report_between_boundaries_matches_none() -> None:
    s = FdiSchedule(2.5)
    assert [s.boundary_at(t) for t in (0.0, 2.5, 3.0, 5.0, 6.0)] == [0, 1, None, 2, None]
