"""The main detector's guidance and attitude tests, fused with the information test (issue 15:
as the map saturates the information metric alone loses the orbit actuator faults).  Each
compares one item of a window's identification evidence (``ground/fdir/identify.Evidence``)
with the nominal bound the scenario states for it (``Tolerances``): the nav estimate's distance
from the plan, the pointing error the attitude estimate reports while tracking, and the Δv the
observer commands per second while holding its PRO.  The nav's own consistency test
(:func:`nis_test`) joins them: an orbit actuator fault is an unmodelled force in the nav
filter, so its innovations grow before the information metric or the Δv spent show it on a
saturated map.  A window fails the detector when the information test or any of these fails;
the verdict names which.
"""

from __future__ import annotations

from collections.abc import Sequence

from ground.fdir.baselines import nis_window_test
from ground.fdir.identify import Evidence, Tolerances


def failed_tests(ev: Evidence, tol: Tolerances) -> tuple[str, ...]:
    """Names of the consistency tests the window's evidence fails, by the names a window's
    verdict gives them (``interfaces.contracts.messages.WINDOW_TESTS``)."""
    failed = []
    if (ev.nav_vs_plan_m or 0.0) > tol.position_m:
        failed.append("plan")
    if (ev.pointing_error_deg or 0.0) > tol.pointing_deg:
        failed.append("pointing")
    if (ev.dv_rate_mps2 or 0.0) > tol.dv_rate_mps2:
        failed.append("dv_rate")
    return tuple(failed)


MIN_NIS_UPDATES = 5
"""Fewer nav updates than this in a window give no NIS verdict (a window cut by a reset or a
data gap)."""


def nis_test(nis: Sequence[float], q: float) -> tuple[float, float] | None:
    """The nav's consistency over one window: (Σ NIS of its N measurement updates, the χ²(6N)
    quantile at 1 − ``q``), the same statistic as the ``chi2_nis`` baseline but at the main
    detector's per-window false-alarm probability q (``hardware_threshold.window_false_alarm``);
    None with fewer than ``MIN_NIS_UPDATES`` updates."""
    return nis_window_test(nis, q) if len(nis) >= MIN_NIS_UPDATES else None
