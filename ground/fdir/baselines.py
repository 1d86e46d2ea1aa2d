"""Baseline detectors, run beside the information-cost FDIR and scored the same way (issue 5):
what an engineer would otherwise put on the ground.

* ``chi2_nis``: the classical navigation consistency test.  Each observer's nav filter reports
  the normalized innovation squared (NIS) of every measurement update, χ²(m) with m = 6 when
  the filter is consistent; over an FDI window the sum of N of them is χ²(N m), so the window
  is inconsistent when the sum exceeds the (1 − α) quantile (:func:`nis_window_test`).  It sees
  what disturbs the nav filter (a sensor bias step, unmodelled forces) and nothing of the
  camera.
* ``cusum``: Page's two-sided CUSUM on the per-window information residual
  r = 1 − ΔH_i/ΔH_i^pred (the signed H_m,i of Eq. 9), with drift ν and alarm level h
  (:class:`Cusum`): g⁺ = max(0, g⁺ + r − ν), g⁻ = max(0, g⁻ − r − ν), alarm when either
  exceeds h.  Slow, small faults accumulate; a large one alarms in one window.
* ``fixed_threshold``: H_m,i against a fixed level (no adaptive threshold, no persistence).

Pure functions and small state; ``ground/apps/baselines.py`` feeds them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from gnc.chi2 import chi2_quantile

NIS_DOF = 6
"""Measurement dimension of the relative-navigation update (position and velocity)."""


def nis_window_test(nis: Sequence[float], alpha: float,
                    dof: int = NIS_DOF) -> tuple[float, float] | None:
    """(Σ NIS, its χ²(N·dof) quantile at 1 − ``alpha``) over one window's N updates, or None
    without any update."""
    if not nis:
        return None
    return float(sum(nis)), float(chi2_quantile(1.0 - alpha, dof * len(nis)))


@dataclass
class Cusum:
    """Two-sided CUSUM per spacecraft on a residual with drift ``drift`` and alarm level
    ``threshold``.  It alarms once per episode, as the other detectors are scored: when the
    statistic first crosses the level, re-armed when it falls back to or below it."""

    drift: float
    threshold: float
    _g: dict[int, tuple[float, float]] = field(default_factory=dict)
    _above: set[int] = field(default_factory=set)

    def update(self, spacecraft: int, residual: float) -> tuple[float, bool, bool]:
        """Add one window's residual; returns (max(g⁺, g⁻), above the level, alarm)."""
        hi, lo = self._g.get(spacecraft, (0.0, 0.0))
        hi = max(0.0, hi + residual - self.drift)
        lo = max(0.0, lo - residual - self.drift)
        self._g[spacecraft] = (hi, lo)
        stat = max(hi, lo)
        above = stat > self.threshold
        alarm = above and spacecraft not in self._above
        if above:
            self._above.add(spacecraft)
        else:
            self._above.discard(spacecraft)
        return stat, above, alarm
