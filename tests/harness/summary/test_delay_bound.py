"""Each fault's delay bound (harness/summary/delay_bound.py) against its closed form: D the
image's δ²/2σ² from the first whole faulty window's ratio and the scan's per-image σ, plus the
nav update's 3(λ − 1); the bound log γ / D steps with γ = 1 / (2 L Φ(−c)), at least one."""

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
GAMMA = 1.0 / (2 * len(SCAN_LENGTHS) * ndtr(-C))


def _window(sc: int, a: float, ratio: float | None, sigma: float | None = None,
            nis_per_update: float | None = None) -> FdirWindow:
    """Window [a, a + 30) of observer ``sc``: its ratio ΔH/ΔH^pred about a nominal mean 0.9,
    the scan's record when ``sigma`` is given, and 30 nav updates of that mean NIS."""
    scan = {} if sigma is None else {"scan_z_max": 1.0, "scan_threshold": C,
                                     "image_sigma": sigma}
    info = {} if ratio is None else {"dh": 0.9 * ratio * 2.0, "dh_pred": 2.0, "ratio_mean": 0.9}
    nis = {} if nis_per_update is None else {"nis_sum": 30 * nis_per_update, "nis_updates": 30,
                                             "nis_limit": 267.0}  # χ²(180) at about 1e-7
    return FdirWindow(sender="ground", t_sim=a + 30.0, spacecraft=sc, t_start_s=a,
                      t_end_s=a + 30.0, images=30, **info, **scan, **nis)


def _fault(start_s: float, end_s: float | None = None, sc: int = 1) -> Fault:
    return Fault(kind="camera_degradation", spacecraft=sc, start_s=start_s, end_s=end_s,
                 magnitude=0.8)


def test_the_bound_is_log_gamma_over_the_divergence() -> None:
    """A 1% shift against σ = 0.8%: D = 0.78 nats, the bound log γ / D (about 18 images);
    the window before the onset and the one it falls in are not used."""
    windows = [_window(1, 0.0, 1.0, 0.008), _window(1, 30.0, 0.5, 0.008),
               _window(1, 60.0, 1.01, 0.008), _window(1, 90.0, 0.9, 0.008)]
    bound = fault_bound(_fault(45.0), windows, 1.0)
    assert bound is not None and bound.nis is None
    assert bound.image == pytest.approx(0.01**2 / (2 * 0.008**2))
    assert bound.delay_s == pytest.approx(math.log(GAMMA) / bound.image)
    assert 17.0 < bound.delay_s < 19.0


def test_a_large_shift_is_bounded_by_one_step() -> None:
    """β = 0.8 (δ = −0.2) against σ = 1%: D = 200 nats, below one step: one step."""
    bound = fault_bound(_fault(0.0), [_window(1, 0.0, 0.8, 0.01)], 0.5)
    assert bound is not None and bound.image == pytest.approx(200.0) and bound.delay_s == 0.5


def test_the_nav_s_evidence_adds_to_the_image_s() -> None:
    """The window's NIS 4 × 6 per update, its NIS test failed: 3(4 − 1) = 9 nats per update,
    beside the ratio's 0.78: the bound is log γ / 9.78; a NIS within its test's limit adds
    nothing (a nominal NIS's noise would reach log γ by chance, summed)."""
    windows = [_window(1, 60.0, 1.01, 0.008, nis_per_update=24.0)]
    bound = fault_bound(_fault(45.0), windows, 1.0)
    assert bound is not None and bound.nis == pytest.approx(9.0)
    assert bound.delay_s == pytest.approx(math.log(GAMMA) / (9.0 + bound.image))
    calm = fault_bound(_fault(45.0), [_window(1, 60.0, 1.01, 0.008, nis_per_update=6.5)], 1.0,
                       [(45.0 + k, 30.0) for k in range(20)])  # noise that sums high
    assert calm is not None and calm.nis == pytest.approx(0.25)  # (6.5 − 6) / 2
    assert calm.delay_s == pytest.approx(math.log(GAMMA) / calm.image)


def test_the_scan_record_comes_from_the_nearest_window_that_has_one() -> None:
    """The faulty window was not scored (its observer declared): σ from the nearest one; a
    σ of 0 (a noise-free camera seeing nothing) is no record."""
    windows = [_window(1, 0.0, 1.0, 0.02), _window(1, 30.0, 1.01), _window(1, 60.0, 1.0, 0.0),
               _window(1, 120.0, 1.0, 0.01), _window(2, 30.0, 1.0, 0.001)]
    bound = fault_bound(_fault(30.0), windows, 1.0)
    assert bound is not None and bound.image == pytest.approx(0.01**2 / (2 * 0.02**2))


def test_no_bound_without_a_faulty_window_a_scan_record_or_a_divergence() -> None:
    assert fault_bound(_fault(100.0), [_window(1, 0.0, 1.0, 0.01)], 1.0) is None
    assert fault_bound(_fault(0.0), [_window(1, 0.0, 1.0)], 1.0) is None
    assert fault_bound(_fault(0.0), [_window(1, 0.0, None, 0.01)], 1.0) is None
    assert fault_bound(_fault(0.0), [_window(1, 0.0, 1.0, 0.01)], 1.0) is None  # D = 0
    # a fault over by the first whole window after its onset: nothing of it to measure
    assert fault_bound(_fault(10.0, 20.0), [_window(1, 30.0, 0.8, 0.01)], 1.0) is None


def test_scores_gain_the_bound_only_where_it_is_known() -> None:
    faults = [_fault(0.0), _fault(500.0, sc=2)]
    scores = score(faults, [Alarm(1, 1.0, "camera", None, "sequential")], [], 30.0)
    out = with_delay_bounds(scores, faults, [_window(1, 0.0, 0.8, 0.01)], 1.0)
    first, second = out.per_fault
    assert first.detector == "sequential" and first.delay_bound_s == 1.0
    assert "delay_bound_s" in first.model_fields_set
    assert "nis_divergence" not in first.model_fields_set  # no NIS summed
    assert second.delay_bound_s is None and "delay_bound_s" not in second.model_fields_set
    assert "detector" not in second.model_fields_set  # no alarm: nothing declared it


def test_summed_update_by_update_the_bound_follows_a_growing_fault() -> None:
    """A NIS growing from the onset at 100 s by 4 a second: (NIS_k − 6)/2 = 2k nats at the
    k-th update, their sum k(k + 1) first reaches log γ (≈ 14.4) at the 4th: 3 s after the
    first update at the onset; the window's mean alone (NIS 30: 12 nats a step) would say
    log γ / 12 ≈ 1.2 steps.  Updates before the onset or after the fault's end do not
    count."""
    fault = _fault(100.0)
    updates = [(99.0, 500.0)] + [(100.0 + k, 6.0 + 4.0 * (k + 1)) for k in range(10)]
    window = _window(1, 100.0, 1.0005, 0.01, nis_per_update=30.0)
    bound = fault_bound(fault, [window], 1.0, updates)
    assert bound is not None and bound.delay_s == pytest.approx(3.0)
    by_mean = math.log(GAMMA) / (12.0 + bound.image)  # no updates: the window's means
    assert fault_bound(fault, [window], 1.0).delay_s == pytest.approx(by_mean)  # type: ignore[union-attr]
    # never summed to log γ while the fault lasted: no bound
    assert fault_bound(_fault(100.0, end_s=101.5), [window], 1.0, updates) is None


def test_each_update_counts_the_image_divergence_of_its_own_window() -> None:
    """The first window after the onset barely moved (D ≈ 0), the next moved by 20% (D = 200):
    with updates that add nothing, the sum reaches log γ at the next window's first update,
    30 s after the onset, not at once as the first whole window's mean would have it."""
    fault = _fault(100.0)
    windows = [_window(1, 100.0, 1.0005, 0.01, nis_per_update=30.0), _window(1, 130.0, 0.8)]
    updates = [(100.0 + k, 6.0) for k in range(40)]
    bound = fault_bound(fault, windows, 1.0, updates)
    assert bound is not None and bound.delay_s == pytest.approx(30.0)
