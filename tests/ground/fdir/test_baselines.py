"""Baseline detectors on constructed cases: the windowed NIS test against the χ² law it
assumes, and CUSUM's accumulation of small residuals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from gnc.hardware_threshold import window_false_alarm
from ground.fdir.baselines import NIS_DOF, Cusum, nis_window_test
from ground.fdir.consistency import MIN_NIS_UPDATES, nis_test


def test_nis_window_false_alarm_rate_matches_alpha() -> None:
    """Consistent filter: NIS ~ χ²(6) per update; windows of 100 updates exceed their quantile
    at the rate α."""
    rng = np.random.default_rng(11)
    alpha = 0.05
    trials = 4000
    hits = 0
    for _ in range(trials):
        stat, thr = nis_window_test(list(rng.chisquare(NIS_DOF, 100)), alpha)  # type: ignore[misc]
        hits += stat > thr
    assert hits / trials == pytest.approx(alpha, abs=0.01)


def test_nis_window_threshold_and_empty() -> None:
    stat, thr = nis_window_test([6.0, 6.0, 6.0], 1e-3)  # type: ignore[misc]
    assert stat == 18.0 and thr == pytest.approx(chi2.ppf(0.999, 18))
    assert nis_window_test([], 1e-3) is None


def test_the_main_detectors_nis_test_holds_the_budget_it_shares() -> None:
    """The main detector's NIS test (fdir.fuse_nis) at q, half the window's budget: a
    consistent filter's 30-update windows exceed at q (at an inflated q, to count); a window
    cut short gives no verdict; an unmodelled force (NIS ×3) exceeds at the default q."""
    q = window_false_alarm(0.01, 30.0, 1, tests=2)
    assert q == pytest.approx(0.01 * 30.0 / 3600.0 / 2.0)
    rng = np.random.default_rng(5)
    windows = [list(rng.chisquare(NIS_DOF, 30)) for _ in range(20000)]
    hits = [nis_test(w, 0.01) for w in windows]
    assert sum(s > t for s, t in hits) / len(windows) == pytest.approx(0.01, abs=0.002)  # type: ignore[misc]
    assert nis_test([6.0] * (MIN_NIS_UPDATES - 1), q) is None
    stat, limit = nis_test([3.0 * v for v in windows[0]], q)  # type: ignore[misc]
    assert stat > limit


def test_cusum_accumulates_a_small_bias_and_ignores_noise_within_the_drift() -> None:
    c = Cusum(drift=0.02, threshold=0.16)
    assert not any(c.update(1, r)[1] for r in [0.015, -0.015] * 50)  # within the drift
    alarms = [c.update(2, 0.05)[2] for _ in range(10)]  # 0.03 net per window
    assert alarms == [False] * 5 + [True] + [False] * 4  # 6 × 0.03 > 0.16 > 5 × 0.03; once
    stat, above, alarm = c.update(3, -0.5)  # one large window, either sign
    assert above and alarm and stat == pytest.approx(0.48)
    assert c.update(3, -0.5)[1:] == (True, False)  # the same episode
    for _ in range(60):  # the fault ends: the sum drains below the level, re-armed
        stat, above, alarm = c.update(3, 0.0)
    assert stat == 0.0 and not above
    assert c.update(3, 0.5)[1:] == (True, True)  # a new episode alarms again
