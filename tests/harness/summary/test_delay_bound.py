"""Each fault's delay bound (harness/summary/delay_bound.py) against its closed form: D =
δ²/2σ² from the first whole faulty window's ratio and the scan's per-image σ, the bound
log γ / D images with γ = 1 / (2 L Φ(−c)), at least one image."""

from __future__ import annotations

import math

import pytest
from scipy.special import ndtr

from gnc.sequential_test import SCAN_LENGTHS
from harness.summary.delay_bound import fault_bound, with_delay_bounds
from harness.summary.scoring import Alarm, score
from interfaces.contracts.messages import FdirWindow
from interfaces.contracts.scenario import Fault

C = 5.25


def _window(sc: int, a: float, ratio: float | None, sigma: float | None = None) -> FdirWindow:
    """Window [a, a + 30) of observer ``sc``: its ratio ΔH/ΔH^pred about a nominal mean 0.9,
    and the scan's record when ``sigma`` is given."""
    scan = {} if sigma is None else {"scan_z_max": 1.0, "scan_threshold": C,
                                     "image_sigma": sigma}
    info = {} if ratio is None else {"dh": 0.9 * ratio * 2.0, "dh_pred": 2.0, "ratio_mean": 0.9}
    return FdirWindow(sender="ground", t_sim=a + 30.0, spacecraft=sc, t_start_s=a,
                      t_end_s=a + 30.0, images=30, **info, **scan)


def _fault(start_s: float, sc: int = 1) -> object:
    faults = [Fault(kind="camera_degradation", spacecraft=sc, start_s=start_s, magnitude=0.8)]
    return score(faults, [Alarm(sc, start_s + 1.0, "camera")], [], 30.0).per_fault[0]


def test_the_bound_is_log_gamma_over_the_divergence() -> None:
    """A 1% shift against σ = 0.8%: D = 0.78 nats, the bound log γ / D images (γ ≈ 1.0e6,
    about 18 images); the window before the onset and the one it falls in are not used."""
    windows = [_window(1, 0.0, 1.0, 0.008), _window(1, 30.0, 0.5, 0.008),
               _window(1, 60.0, 1.01, 0.008), _window(1, 90.0, 0.9, 0.008)]
    divergence, nis, bound_s = fault_bound(_fault(45.0), windows, 1.0)  # type: ignore[arg-type]
    assert nis is None
    assert divergence == pytest.approx(0.01**2 / (2 * 0.008**2))
    gamma = 1.0 / (2 * len(SCAN_LENGTHS) * ndtr(-C))
    assert bound_s == pytest.approx(math.log(gamma) / divergence)
    assert 17.0 < bound_s < 19.0


def test_a_large_shift_is_bounded_by_one_image() -> None:
    """β = 0.8 (δ = −0.2) against σ = 1%: D = 200 nats, below one image: one image."""
    divergence, _, bound_s = fault_bound(_fault(0.0), [_window(1, 0.0, 0.8, 0.01)],  # type: ignore[arg-type]
                                         0.5)
    assert divergence == pytest.approx(200.0)
    assert bound_s == 0.5


def test_the_scan_record_comes_from_the_nearest_window_that_has_one() -> None:
    """The faulty window was not scored (its observer declared): σ from the nearest one."""
    windows = [_window(1, 0.0, 1.0, 0.02), _window(1, 30.0, 1.01), _window(1, 90.0, 1.0, 0.01),
               _window(2, 30.0, 1.0, 0.001)]
    divergence, _, _ = fault_bound(_fault(30.0), windows, 1.0)  # type: ignore[arg-type]
    assert divergence == pytest.approx(0.01**2 / (2 * 0.02**2))


def test_the_nis_s_growth_bounds_the_delay_where_it_says_more() -> None:
    """The window's NIS 4× its mean over 30 updates: D = 3(4 − 1 − ln 4) = 4.84 nats per
    update, against the ratio's 0.78: the bound is log γ / 4.84."""
    window = _window(1, 60.0, 1.01, 0.008).model_copy(
        update={"nis_sum": 4.0 * 6 * 30, "nis_updates": 30})
    divergence, nis, bound_s = fault_bound(_fault(45.0), [window], 1.0)  # type: ignore[arg-type]
    assert nis == pytest.approx(3.0 * (3.0 - math.log(4.0)))
    gamma = 1.0 / (2 * len(SCAN_LENGTHS) * ndtr(-C))
    assert bound_s == pytest.approx(math.log(gamma) / nis) and nis > divergence
    calm = window.model_copy(update={"nis_sum": 0.5 * 6 * 30})  # a NIS that fell: no evidence
    assert fault_bound(_fault(45.0), [calm], 1.0)[1] == 0.0  # type: ignore[arg-type, index]


def test_no_bound_without_a_faulty_window_or_a_scan_record() -> None:
    assert fault_bound(_fault(100.0), [_window(1, 0.0, 1.0, 0.01)], 1.0) is None  # type: ignore[arg-type]
    assert fault_bound(_fault(0.0), [_window(1, 0.0, 1.0)], 1.0) is None  # type: ignore[arg-type]
    assert fault_bound(_fault(0.0), [_window(1, 0.0, None, 0.01)], 1.0) is None  # type: ignore[arg-type]


def test_scores_gain_the_bound_only_where_it_is_known() -> None:
    faults = [Fault(kind="camera_degradation", spacecraft=1, start_s=0.0, magnitude=0.8),
              Fault(kind="camera_degradation", spacecraft=2, start_s=500.0, magnitude=0.8)]
    scores = score(faults, [Alarm(1, 1.0, "camera", None, "sequential")], [], 30.0)
    out = with_delay_bounds(scores, [_window(1, 0.0, 0.8, 0.01)], 1.0)
    first, second = out.per_fault
    assert first.detector == "sequential" and first.delay_bound_s == 1.0
    assert "delay_bound_s" in first.model_fields_set
    assert second.delay_bound_s is None and "delay_bound_s" not in second.model_fields_set
    assert "detector" not in second.model_fields_set  # no alarm: nothing declared it
