"""The nav's consistency test, fused with the window test (``gnc/window_test.py``: the
information test and the guidance and attitude tests, issue 15) with ``fdir.fuse_nis``: an
orbit actuator fault is an unmodelled force in the nav filter, so its innovations grow before
the information metric or the Δv spent show it on a saturated map.  A window fails the
detector when the information test or any of these fails; the verdict names which.
"""

from __future__ import annotations

from collections.abc import Sequence

from ground.fdir.baselines import nis_window_test

MIN_NIS_UPDATES = 5
"""Fewer nav updates than this in a window give no NIS verdict (a window cut by a reset or a
data gap)."""


def nis_test(nis: Sequence[float], q: float) -> tuple[float, float] | None:
    """The nav's consistency over one window: (Σ NIS of its N measurement updates, the χ²(6N)
    quantile at 1 − ``q``), the same statistic as the ``chi2_nis`` baseline but at the main
    detector's per-window false-alarm probability q (``hardware_threshold.window_false_alarm``);
    None with fewer than ``MIN_NIS_UPDATES`` updates."""
    return nis_window_test(nis, q) if len(nis) >= MIN_NIS_UPDATES else None
