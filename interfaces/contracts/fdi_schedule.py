"""The FDI window schedule, owned in one place by everyone who needs it: the observers' H_i
reports (``fsw.apps.infocost``), the ground's FDIR and baselines (``ground.apps``).

Window k covers sim time [k·P, (k+1)·P), P = ``rates.fdi_period_s``; boundary j is t = j·P
(window j−1 closes there).  Windows and boundaries are integers; a time is matched to a
boundary within a tolerance, never by float equality.  The scenario requires P to be a whole
number of ω_mid periods (``Rates``), so every boundary falls on a step of the ω_mid apps that
report and judge there.
"""

from __future__ import annotations

from dataclasses import dataclass

TOLERANCE = 1e-6
"""A time within this fraction of a period from a boundary is at the boundary."""


@dataclass(frozen=True)
class FdiSchedule:
    period_s: float

    def start(self, k: int) -> float:
        """Start of window k (s)."""
        return k * self.period_s

    def end(self, k: int) -> float:
        """End of window k (s), boundary k + 1."""
        return (k + 1) * self.period_s

    def boundary_at(self, t_s: float) -> int | None:
        """The boundary j with j·P = ``t_s`` (within ``TOLERANCE`` of a period), else None."""
        j = round(t_s / self.period_s)
        return j if abs(t_s / self.period_s - j) <= TOLERANCE else None
