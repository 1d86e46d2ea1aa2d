"""The sequential per-image test (gnc/sequential_test.py) against closed forms, the reference's
worked numbers and a seeded simulation of its own null model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ndtr, ndtri
from scipy.stats import chi2

from gnc.sequential_test import (
    SCAN_LENGTHS,
    chi2_scan,
    chi2_span_limit,
    delay_bound,
    image_evidence,
    kl_gaussian_shift,
    kl_nis_growth,
    scan_false_alarm,
    scan_statistic,
    scan_threshold,
)


def test_the_threshold_is_the_union_bound_over_the_spans() -> None:
    q = 1e-5
    c = scan_threshold(q)
    assert 2 * len(SCAN_LENGTHS) * ndtr(-c) == pytest.approx(q, rel=1e-9)
    assert scan_threshold(q, (1,)) == pytest.approx(-ndtri(q / 2))
    assert scan_false_alarm(c) == pytest.approx(q, rel=1e-9)


def _scans(r: np.ndarray, sigma_e: float, sigma_b: float) -> np.ndarray:
    """max |Z_n| at every image of every run of ``r`` (runs × images), from the longest span
    on: the scan of :func:`scan_statistic`, vectorised over runs and images."""
    cums = np.concatenate([np.zeros((len(r), 1)), np.cumsum(r, axis=1)], axis=1)
    z = np.zeros(r.shape)
    for n in SCAN_LENGTHS:
        means = (cums[:, n:] - cums[:, :-n]) / n
        z[:, n - 1:] = np.maximum(z[:, n - 1:],
                                  np.abs(means) / math.sqrt(sigma_b**2 + sigma_e**2 / n))
    return z[:, max(SCAN_LENGTHS) - 1:]


def _null_residuals(sigma_e: float, sigma_b: float, correlation: float, images: int,
                    runs: int, rng: np.random.Generator) -> np.ndarray:
    """Simulated nominal residuals (runs × images): the pose effect an AR(1) process of 1σ
    σ_b and lag-1 ``correlation`` (1: constant over the run), the camera's noise white."""
    b = np.empty((runs, images))
    b[:, 0] = rng.normal(0.0, sigma_b, runs)
    innovation = sigma_b * math.sqrt(1.0 - correlation**2)
    for k in range(1, images):
        b[:, k] = correlation * b[:, k - 1] + rng.normal(0.0, innovation, runs)
    return b + rng.normal(0.0, sigma_e, (runs, images))


@pytest.mark.parametrize(("sigma_e", "sigma_b", "correlation"), [
    (0.002, 0.005, 1.0), (0.002, 0.005, 0.55), (0.002, 0.005, 0.0), (0.009, 0.002, 0.55),
    (0.01, 0.0, 0.0)])
def test_the_threshold_holds_its_budget_whatever_the_pose_correlation(
        sigma_e: float, sigma_b: float, correlation: float) -> None:
    """The nominal model simulated with the pose effect constant, correlated as the paper's
    set-up measures it (0.55 image to image) and white: no more crossings per image than
    the budget (the simulated scan checked against :func:`scan_statistic` on some runs)."""
    q = 2e-3
    r = _null_residuals(sigma_e, sigma_b, correlation, 96, 4000, np.random.default_rng(41))
    z = _scans(r, sigma_e, sigma_b)
    for run, image in [(0, 0), (1, 40), (2, 64), (3, 5)]:
        k = image + max(SCAN_LENGTHS)
        scan = scan_statistic(r[run, :k], sigma_e, sigma_b)
        assert scan is not None and scan.z == pytest.approx(z[run, image], rel=1e-9)
    assert float(np.mean(z > scan_threshold(q))) <= q


def test_the_scan_takes_the_span_that_holds_the_shift() -> None:
    residuals = np.array([0.0, 0.0, 0.0, 0.0, -0.03, -0.03])
    result = scan_statistic(residuals, 0.002, 0.005)
    assert result is not None and result.span == 2
    assert result.signed == pytest.approx(-0.03 / math.sqrt(0.005**2 + 0.002**2 / 2))
    assert result.z == -result.signed
    mixed = scan_statistic(residuals, np.array([0.001] * 5 + [0.004]),
                           np.array([0.01] * 4 + [0.002, 0.004]))
    assert mixed is not None and mixed.span == 2  # S_2² = (mean σ_b)² + Σσ_e² / 4
    assert mixed.signed == pytest.approx(-0.03 / math.sqrt(0.003**2 + (0.001**2 + 0.004**2) / 4))
    assert scan_statistic(np.array([]), 0.002, 0.005) is None


def test_an_image_s_evidence_is_its_gain_against_the_prediction() -> None:
    """Two POIs of weights 1 and 3 (ΔH^pred 4): a gain of 3.6 at μ = 0.9 is no change;
    σ_e = √(v (1 + 9)) / 4; an image the twin predicts nothing of is dropped."""
    weights = np.array([[1.0, 3.0], [0.0, 0.0], [2.0, 2.0]])
    evidence = image_evidence(np.array([3.6, 1.0, 2.88]), weights, 0.9, 0.0025)
    assert evidence.kept.tolist() == [True, False, True]
    assert evidence.residuals == pytest.approx([0.0, -0.2])
    assert evidence.sigma_e == pytest.approx([math.sqrt(0.0025 * 10) / 4,
                                              math.sqrt(0.0025 * 8) / 4])


def test_a_degraded_camera_crosses_on_its_first_image() -> None:
    """β = 0.8 moves an image's gain by 20%: against σ_b 0.5% and σ_e 0.2% one image is
    ~37σ, far beyond any budget's threshold."""
    rng = np.random.default_rng(7)
    nominal = rng.normal(0.0, 0.002, 40) + 0.004
    c = scan_threshold(1e-6)
    before = [scan_statistic(nominal[: k + 1], 0.002, 0.005) for k in range(40)]
    assert max(s.z for s in before if s is not None) < c
    after = scan_statistic(np.append(nominal, -0.2), 0.002, 0.005)
    assert after is not None and after.z > c and after.signed < 0 and after.span == 1


def test_the_delay_bound_gives_the_reference_numbers() -> None:
    """../shared/REFERENCE.md: γ ≈ 3e4 samples is log γ ≈ 10.3 nats; a 1σ shift has D = 0.5
    and needs ≈ 21 samples; a 100σ shift, D = 5000, less than one."""
    gamma = 3e4
    assert math.log(gamma) == pytest.approx(10.3, abs=0.05)
    assert kl_gaussian_shift(0.002, 0.002) == pytest.approx(0.5)
    assert delay_bound(gamma, kl_gaussian_shift(0.002, 0.002)) == pytest.approx(20.6, abs=0.1)
    assert delay_bound(gamma, kl_gaussian_shift(0.2, 0.002)) < 1.0
    assert delay_bound(gamma, 0.0) == math.inf


def test_the_nis_growth_s_divergence_is_the_innovation_mean_shift_s() -> None:
    """KL(N(μ, S) ‖ N(0, S)) = ½ μᵀS⁻¹μ by its general form, with the NIS's mean d + μᵀS⁻¹μ;
    a covariance grown instead to the same NIS mean diverges less; nothing for a NIS that did
    not grow."""
    cov = np.diag([1.0, 4.0, 9.0])
    mu = np.array([1.0, -2.0, 3.0])
    shift = 0.5 * float(mu @ np.linalg.solve(cov, mu))
    mean_nis = 3.0 + float(mu @ np.linalg.solve(cov, mu))
    assert kl_nis_growth(mean_nis, 3) == pytest.approx(shift)
    lam = mean_nis / 3.0
    assert 1.5 * (lam - 1.0 - math.log(lam)) < kl_nis_growth(mean_nis, 3)
    assert kl_nis_growth(6.0, 6) == 0.0 and kl_nis_growth(3.0, 6) == 0.0


@pytest.mark.parametrize(("call", "match"), [
    (lambda: scan_threshold(0.0), "in \\(0, 1\\)"),
    (lambda: scan_threshold(1.0), "in \\(0, 1\\)"),
    (lambda: kl_gaussian_shift(0.1, 0.0), "sigma must be positive"),
    (lambda: delay_bound(1.0, 0.5), "gamma must exceed 1"),
])
def test_bad_settings_are_refused(call, match: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=match):
        call()


def test_the_chi2_scan_is_the_normal_score_of_each_span_s_tail() -> None:
    """Four NIS values of 6 (their mean): span n sums 6n, z_n = Φ⁻¹(P(χ²(6n) ≤ 6n)), the
    largest at n = 1 (the mean lies further above the median the fewer the degrees); the
    last one 30: span 1, z_1 = Φ⁻¹(P(χ²(6) ≤ 30))."""
    flat = chi2_scan([6.0, 6.0, 6.0, 6.0], 6)
    assert flat is not None and flat.span == 1
    assert flat.z == pytest.approx(max(ndtri(chi2.cdf(6.0 * n, 6 * n)) for n in (1, 2, 4)))
    jump = chi2_scan([6.0, 6.0, 6.0, 30.0], 6)
    assert jump is not None and jump.span == 1
    assert jump.z == pytest.approx(ndtri(chi2.cdf(30.0, 6)))
    assert chi2_scan([], 6) is None
    assert chi2_scan([1e6], 6).z == pytest.approx(-ndtri(1e-300))  # the tail's floor
    c = scan_threshold(1e-5, sides=1)
    assert chi2_span_limit(c, 6, 4) == pytest.approx(chi2.isf(1e-5 / len(SCAN_LENGTHS), 24))


def test_the_chi2_scan_holds_its_budget_on_nominal_nis() -> None:
    """χ²(6) draws, independent: no more crossings per update than the one-sided budget (the
    scan vectorised over runs and updates, checked against :func:`chi2_scan` on some)."""
    q = 0.01
    values = np.random.default_rng(43).chisquare(6, (3000, 96))
    cums = np.concatenate([np.zeros((len(values), 1)), np.cumsum(values, axis=1)], axis=1)
    z = np.full(values.shape, -np.inf)
    for n in SCAN_LENGTHS:
        z[:, n - 1:] = np.maximum(z[:, n - 1:],
                                  ndtri(chi2.cdf(cums[:, n:] - cums[:, :-n], 6 * n)))
    for run, k in [(0, 40), (1, 95), (2, 31)]:
        assert chi2_scan(values[run, : k + 1], 6).z == pytest.approx(z[run, k], rel=1e-9)
    assert float(np.mean(z[:, 31:] > scan_threshold(q, sides=1))) <= q


def test_a_growing_nis_crosses_within_a_few_updates() -> None:
    """An unmodelled force: innovations 5× their 1σ (NIS 25× its mean) cross on the second
    update at a budget of 1e-6 per update."""
    c = scan_threshold(1e-6, sides=1)
    values = [6.0] * 20 + [150.0, 150.0, 150.0]
    crossed = [k for k in range(20, 23) if chi2_scan(values[: k + 1], 6).z > c]
    assert crossed and crossed[0] <= 21


@pytest.mark.parametrize("seed", range(3))
def test_the_compiled_scan_gives_the_references_bits(seed: int) -> None:
    """``ScanBuffer.scan`` runs :func:`scan_compiled`: the same statistic, sign and span as
    :func:`scan_statistic` to the bit, on any number of residuals up to the longest span,
    with zero residuals and with a zero spread (NaN, as numpy's argmax takes it)."""
    from gnc.sequential_test import _LENGTHS, ScanBuffer, scan_compiled

    rng = np.random.default_rng(seed)
    for trial in range(1000):
        k = int(rng.integers(1, 40))
        r = rng.normal(size=k) * 10.0 ** rng.integers(-4, 2)
        se, sb = rng.uniform(0.0, 0.1, k), rng.uniform(0.001, 0.05, k)
        if trial % 7 == 0:
            r[:] = 0.0
        if trial % 11 == 0:
            se[-1] = sb[-1] = 0.0
        with np.errstate(divide="ignore", invalid="ignore"):  # a zero spread: inf, NaN
            want = scan_statistic(r, se, sb)
        got = scan_compiled(r, se, sb, _LENGTHS)
        assert want is not None
        assert np.array_equal([want.z, want.signed], got[:2], equal_nan=True)
        assert want.span == got[2], trial
    assert ScanBuffer().scan() is None
