"""Tests of the onboard attitude MEKF (fsw.lib.mekf) with the sim gyro and star tracker.

References: the matrix exponential of the continuous error dynamics (scipy.linalg.expm) for Φ
and Van Loan's method for Q; the scalar Kalman gain for an isotropic update; the project's
linear Kalman filter (gnc.kalman) for a general update; and Monte Carlo consistency (NEES,
NIS against χ² bounds from scipy.stats) of the filter run on the sim truth (sim.attitude) with the
sim's Farrenkopf gyro and star tracker (sim.sensors), which are separate code.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

from fsw.lib.mekf import error_state, mekf_init, mekf_propagate, mekf_transition, mekf_update
from gnc import kalman
from sim.attitude import AttitudeTruth
from sim.sensors import GYRO_BIAS0_RAD_S, Gyro, StarTracker

DT = 0.1
SIGMA_V = 4.4e-5  # rad/√s
SIGMA_U = 2.4e-7  # rad/s^1.5


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _continuous(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """F and G Qc Gᵀ of δθ̇ = -[w×]δθ - Δb - η_v, Δḃ = η_u (written out here)."""
    F = np.zeros((6, 6))
    F[:3, :3] = -_skew(w)
    F[:3, 3:] = -np.eye(3)
    GQG = np.diag([SIGMA_V**2] * 3 + [SIGMA_U**2] * 3)
    return F, GQG


@pytest.mark.parametrize("w", [[0.0, 0.0, 0.0], [1e-9, -2e-9, 5e-10], [0.01, -0.02, 0.015],
                               [0.3, 0.5, -0.4]])
def test_transition_matches_expm_and_van_loan(w: list[float]) -> None:
    w_arr = np.array(w)
    dt = 0.5
    phi, Q = mekf_transition(w_arr, dt, SIGMA_V, SIGMA_U)
    F, GQG = _continuous(w_arr)
    np.testing.assert_allclose(phi, expm(F * dt), rtol=0, atol=1e-13)
    # Van Loan (1978): expm([[-F, GQGᵀ], [0, Fᵀ]] dt) = [[., Φ⁻¹Q], [0, Φᵀ]].
    M = np.zeros((12, 12))
    M[:6, :6], M[:6, 6:], M[6:, 6:] = -F, GQG, F.T
    E = expm(M * dt)
    Q_exact = E[6:, 6:].T @ E[:6, 6:]
    x = np.linalg.norm(w_arr) * dt

    def rel(rows: slice, cols: slice) -> float:
        return float(np.max(np.abs(Q[rows, cols] - Q_exact[rows, cols]))
                     / np.max(np.abs(Q_exact[rows, cols])))

    att, bias = slice(0, 3), slice(3, 6)
    # The book's Q: bias block exact, attitude block exact in its σv part (rotation-invariant),
    # the cross block -σu² dt²/2 I misses a rotation term of relative size ~ |w| dt / 4.
    assert rel(bias, bias) < 1e-12
    assert rel(att, att) < 1e-12 + 1e-6 * x
    assert rel(att, bias) <= 1e-12 + x / 3.0
    # batch == single
    phis, _ = mekf_transition(np.stack([w_arr, 2 * w_arr]), dt, SIGMA_V, SIGMA_U)
    np.testing.assert_allclose(phis[0], phi, rtol=0, atol=1e-15)


def test_isotropic_update_matches_scalar_gain() -> None:
    p, r = 4e-8, 1e-8
    q0 = Rotation.from_rotvec([0.4, -0.2, 1.0])
    nu = np.array([1e-4, -2e-4, 5e-5])
    q_meas = (q0 * Rotation.from_rotvec(nu)).as_quat()
    P = np.diag([p] * 3 + [1e-10] * 3)
    b = np.array([1e-5, 0.0, -1e-5])
    q1, b1, P1, nis = mekf_update(q0.as_quat(), b, P, -q_meas, r * np.eye(3))  # either sign
    gain = p / (p + r)
    expected = q0 * Rotation.from_rotvec(gain * nu)
    assert (Rotation.from_quat(q1).inv() * expected).magnitude() < 1e-15
    assert q1[3] >= 0.0
    np.testing.assert_array_equal(b1, b)  # no attitude-bias correlation -> bias untouched
    np.testing.assert_allclose(np.diag(P1)[:3], p * r / (p + r), rtol=1e-7)  # reset: O(|δθ|²)
    assert nis == pytest.approx(nu @ nu / (p + r), rel=1e-9)


def test_general_update_matches_linear_kalman_filter() -> None:
    rng = np.random.default_rng(8)
    A = rng.normal(size=(6, 6)) * np.array([1e-4] * 3 + [1e-5] * 3)
    P = A @ A.T + np.diag([1e-9] * 3 + [1e-11] * 3)
    R = np.diag([2e-9, 3e-9, 8e-8])
    q0 = Rotation.random(random_state=rng)
    nu = np.array([3e-5, -1e-4, 2e-4])
    q_meas = (q0 * Rotation.from_rotvec(nu)).as_quat()
    b0 = np.array([2e-5, -1e-5, 3e-6])
    q1, b1, P1, nis = mekf_update(q0.as_quat(), b0, P, q_meas, R)
    H = np.hstack([np.eye(3), np.zeros((3, 3))])
    dx, P_kf, nis_kf = kalman.update(np.zeros(6), P, nu, H, R)
    assert nis == pytest.approx(nis_kf, rel=1e-10)
    np.testing.assert_allclose(b1, b0 + dx[3:], rtol=0, atol=1e-15)
    assert ((q0 * Rotation.from_rotvec(dx[:3])).inv() * Rotation.from_quat(q1)).magnitude() < 1e-15
    G = np.eye(6)
    G[:3, :3] -= 0.5 * _skew(dx[:3])
    np.testing.assert_allclose(P1, G @ P_kf @ G.T, rtol=1e-10, atol=1e-24)
    # Batch of two filters == two single calls.
    qs, bs, Ps, nis_b = mekf_update(np.stack([q0.as_quat()] * 2), np.stack([b0, b0]),
                                    np.stack([P, P]), np.stack([q_meas, q_meas]), R)
    assert np.asarray(nis_b).shape == (2,)
    np.testing.assert_allclose(Ps[1], P1, rtol=1e-12, atol=1e-24)
    np.testing.assert_allclose(qs[0], q1, atol=1e-15)


def test_noise_free_propagation_follows_truth() -> None:
    J = np.diag([0.10, 0.12, 0.05])
    r0 = Rotation.from_rotvec([0.3, 0.8, -0.5])
    w0 = np.deg2rad([0.6, -0.5, 0.7])
    truth = AttitudeTruth(r0.as_quat()[None], w0[None], J, np.zeros((1, 3)))
    q, b, P = mekf_init(np.stack([r0.as_quat()] * 2), 1e-10 * np.eye(3), 1e-6)
    for _ in range(1000):
        r_prev = truth.r_eci_body()[0]
        truth.step(DT, np.zeros((1, 3)))
        increment = (r_prev.inv() * truth.r_eci_body()[0]).as_rotvec() / DT
        # filter 0: the exact rotation increment; filter 1: the mean rate a gyro integrates
        q, b, P = mekf_propagate(q, b, P, np.stack([increment, truth.mean_rate[0]]), DT,
                                 SIGMA_V, SIGMA_U)
    errors = (Rotation.from_quat(q).inv() * truth.r_eci_body()[0]).magnitude()
    assert errors[0] < 1e-11
    # The mean rate ignores coning (~|w x w_dot| dt³/12 per step, systematic): 100 s stay below
    # 0.07 arcsec (measured 1.6e-7 rad; it scales as dt², checked at dt = 0.05 s).
    assert errors[1] < 3e-7
    np.testing.assert_array_equal(b, 0.0)


def test_bad_input_is_rejected() -> None:
    q, b, P = mekf_init([0.0, 0.0, 0.0, 1.0], 1e-8 * np.eye(3), 1e-5)
    with pytest.raises(ValueError):
        mekf_propagate(q, b, P, [np.nan, 0.0, 0.0], DT, SIGMA_V, SIGMA_U)
    with pytest.raises(ValueError):
        mekf_propagate(q, b, P[:3, :3], [0.0, 0.0, 0.0], DT, SIGMA_V, SIGMA_U)
    with pytest.raises(ValueError):
        mekf_propagate(q, b, P, [0.0, 0.0, 0.0], 0.0, SIGMA_V, SIGMA_U)
    with pytest.raises(ValueError):
        mekf_propagate(q, b, P, [0.0, 0.0, 0.0], DT, -1.0, SIGMA_U)
    with pytest.raises(ValueError):
        mekf_update(q, b, P, [0.0, 0.0, 0.0, 0.0], 1e-8 * np.eye(3))
    with pytest.raises(ValueError):
        mekf_update(q, b, P, q, -1e-8 * np.eye(3))
    with pytest.raises(ValueError):
        mekf_update(q, b, P, q, np.array([[1e-8, 1e-9, 0], [0, 1e-8, 0], [0, 0, 1e-8]]))
    with pytest.raises(ValueError):
        mekf_init([0.0, 0.0, 0.0, 1.0], 1e-8 * np.eye(3), 0.0)


# ----- the sim's attitude sensors -------------------------------------------------------


def _streams(n: int, seed: int) -> list[np.random.Generator]:
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n)]


def _var_bounds(m: int) -> tuple[float, float]:
    """99.9 % χ² bounds of a sample variance of m normal draws, as a factor of the variance."""
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], m - 1) / (m - 1)
    return float(lo), float(hi)


def test_gyro_integrated_angle_matches_farrenkopf_continuous_model() -> None:
    """Summed over T = n dt, the discrete samples must reproduce the continuous model's angle
    error: ARW alone gives variance σv² T, the bias random walk alone σu² T³/3 (Farrenkopf)."""
    n_sc, steps, dt = 64, 50, 0.2
    T = steps * dt
    w_true = np.tile([0.01, -0.02, 0.005], (n_sc, 1))
    for sigma_v, sigma_u, expected in ((1e-4, 0.0, 1e-8 * T), (0.0, 1e-5, 1e-10 * T**3 / 3.0)):
        samples = []
        for trial in range(6):  # 6 x 64 x 3 independent angle errors
            gyro = Gyro(_streams(n_sc, 100 + trial), sigma_v, sigma_u, bias0_sigma=1e-4)
            b0 = gyro.bias
            angle = sum(gyro.measure(w_true, dt) - w_true for _ in range(steps)) * dt
            samples.append((angle - b0 * T).ravel())
        x = np.concatenate(samples)
        lo, hi = _var_bounds(x.size)
        assert lo * expected < np.mean(x**2) * x.size / (x.size - 1) < hi * expected
    # The bias itself walks with variance σu² t, and the initial bias has the requested 1σ.
    gyro = Gyro(_streams(n_sc, 7), 0.0, 1e-5, bias0_sigma=3e-4)
    b0 = gyro.bias
    for _ in range(steps):
        gyro.measure(w_true, dt)
    for x, var in (((gyro.bias - b0).ravel(), 1e-10 * T), (b0.ravel(), 9e-8)):
        lo, hi = _var_bounds(x.size)
        assert lo * var < np.mean(x**2) * x.size / (x.size - 1) < hi * var


def test_gyro_per_spacecraft_streams_and_bad_input() -> None:
    alone = Gyro(_streams(3, 1)[:1])
    crowd = Gyro(_streams(3, 1))
    w = np.array([[0.01, 0.0, 0.0], [0.0, 0.3, 0.0], [0.0, 0.0, -0.2]])
    for _ in range(5):
        np.testing.assert_array_equal(alone.measure(w[:1], DT)[0], crowd.measure(w, DT)[0])
    with pytest.raises(ValueError):
        crowd.measure(np.full((3, 3), np.nan), DT)
    with pytest.raises(ValueError):
        crowd.measure(w[:2], DT)
    with pytest.raises(ValueError):
        crowd.measure(w, 0.0)


@pytest.mark.parametrize("axis", [0, 2])
def test_star_tracker_noise_and_timing(axis: int) -> None:
    n = 64
    st = StarTracker(_streams(n, 3), sigma_cross_arcsec=10.0, sigma_about_arcsec=60.0,
                     boresight_axis=axis, rate_hz=3.0)
    sigma = np.full(3, np.deg2rad(10.0 / 3600.0))
    sigma[axis] = np.deg2rad(60.0 / 3600.0)
    np.testing.assert_allclose(st.covariance_body(), np.diag(sigma**2), rtol=1e-15)
    truth = Rotation.random(n, random_state=np.random.default_rng(9))
    due = []
    errors = []
    for k in range(31):  # 10 Hz ticks over 3 s; samples due at 0, 1/3, 2/3, ... s
        z = st.measure(k * DT, truth)
        if z is None:
            continue
        due.append(k)
        assert np.all(z[:, 3] >= 0.0)
        errors.append((truth.inv() * Rotation.from_quat(z)).as_rotvec())
    assert due == [0, 4, 7, 10, 14, 17, 20, 24, 27, 30]
    e = np.concatenate(errors)
    for i in range(3):
        lo, hi = _var_bounds(e.shape[0])
        var = np.mean(e[:, i] ** 2) * e.shape[0] / (e.shape[0] - 1)
        assert lo * sigma[i] ** 2 < var < hi * sigma[i] ** 2
    assert abs(np.corrcoef(e.T)[0, 1]) < 4.0 / np.sqrt(e.shape[0])
    with pytest.raises(ValueError):
        st.sample(truth[:3])


# ----- Monte Carlo on the sim truth with the sim sensors ----------------------------------


def _monte_carlo(
    runs: int, duration_s: float, st_rate_hz: float, seed: int
) -> dict[str, np.ndarray]:
    """Vectorised over the runs: one truth body, gyro and star tracker per run, own streams."""
    ss = np.random.SeedSequence(seed)
    init_ss, gyro_ss, st_ss = ss.spawn(3)
    rng = np.random.default_rng(init_ss)
    J = np.diag([0.10, 0.12, 0.05])
    w0 = rng.normal(size=(runs, 3))
    w0 *= np.deg2rad(1.0) / np.linalg.norm(w0, axis=1, keepdims=True)  # 1 °/s
    q0 = Rotation.random(runs, random_state=rng).as_quat()
    truth = AttitudeTruth(q0, w0, J, np.zeros((runs, 3)))
    gyro = Gyro([np.random.default_rng(s) for s in gyro_ss.spawn(runs)], SIGMA_V, SIGMA_U,
                GYRO_BIAS0_RAD_S)
    st = StarTracker([np.random.default_rng(s) for s in st_ss.spawn(runs)], rate_hz=st_rate_hz)
    R = st.covariance_body()
    first = st.measure(0.0, truth.r_eci_body())
    assert first is not None
    q, b, P = mekf_init(first, R, GYRO_BIAS0_RAD_S)
    steps = int(round(duration_s / DT))
    every = 5  # evaluate the errors every 0.5 s (both just after and between 1 Hz updates)
    nees = np.empty((steps // every, runs))
    err = np.empty((steps // every, runs, 6))
    sig = np.empty((steps // every, runs, 6))
    nis: list[np.ndarray] = []
    for k in range(steps):
        truth.step(DT, np.zeros((runs, 3)))
        q, b, P = mekf_propagate(q, b, P, gyro.measure(truth.mean_rate, DT), DT, SIGMA_V, SIGMA_U)
        z = st.measure((k + 1) * DT, truth.r_eci_body())
        if z is not None:
            q, b, P, s = mekf_update(q, b, P, z, R)
            nis.append(np.asarray(s))
        if (k + 1) % every:
            continue
        # Independent error: δθ from DCMs, Δb from the gyro's true bias.
        i = k // every
        R_est = Rotation.from_quat(q).as_matrix()
        dR = np.einsum("nji,njk->nik", R_est, truth.r_eci_body().as_matrix())
        err[i] = np.concatenate([Rotation.from_matrix(dR).as_rotvec(), gyro.bias - b], axis=1)
        sig[i] = np.sqrt(np.diagonal(P, axis1=1, axis2=2))
        nees[i] = np.einsum("ni,ni->n", err[i], np.linalg.solve(P, err[i][:, :, None])[:, :, 0])
    np.testing.assert_allclose(err[-1], error_state(q, b, truth.q, gyro.bias), atol=1e-15)
    return {"nees": nees, "err": err, "sig": sig, "nis": np.concatenate(nis),
            "st_sigma": st.sigma_rad, "b0_sigma": np.array(GYRO_BIAS0_RAD_S)}


@pytest.mark.parametrize(("st_rate_hz", "duration_s"), [(1.0, 200.0), (10.0, 60.0)])
def test_monte_carlo_consistency(st_rate_hz: float, duration_s: float) -> None:
    """30 runs of a body tumbling at 1 °/s, 10 Hz gyro (ARW 0.15 °/√h, RRW 3 °/h/√h, 10 °/h
    initial bias), star tracker 10"/60" (boresight z) at 1 or 10 Hz."""
    runs = 30
    mc = _monte_carlo(runs, duration_s, st_rate_hz, seed=21)
    # NEES (6 dof) averaged over the runs: runs * mean ~ χ²(6 runs); 95 % two-sided bounds.
    lo, hi = stats.chi2.ppf([0.025, 0.975], 6 * runs) / runs
    mean_nees = mc["nees"].mean(axis=1)
    inside = np.mean((mean_nees > lo) & (mean_nees < hi))
    assert inside > 0.85, (inside, mean_nees.mean())
    # NIS (3 dof): grand mean inside the 99 % bounds of its χ² distribution.
    nis = mc["nis"].ravel()
    lo3, hi3 = stats.chi2.ppf([0.005, 0.995], 3 * nis.size) / nis.size
    assert lo3 < nis.mean() < hi3, nis.mean()
    # Bias: final estimates inside 3σ on (nearly) every axis, and far better than the prior.
    err, sig = mc["err"], mc["sig"]
    assert np.mean(np.abs(err[-1, :, 3:]) < 3.0 * sig[-1, :, 3:]) >= 0.97
    assert np.sqrt(np.mean(err[-1, :, 3:] ** 2)) < 0.25 * mc["b0_sigma"]
    # Attitude after convergence (second half), per body axis: RMS at most the star tracker's
    # noise (x 1.2 margin; measured 0.90 at 1 Hz, 0.51 at 10 Hz across the boresight) and
    # 99 % of the samples within 3x it.
    settled = err[err.shape[0] // 2:, :, :3]
    rms = np.sqrt(np.mean(settled**2, axis=(0, 1)))
    assert np.all(rms < 1.2 * mc["st_sigma"]), rms / mc["st_sigma"]
    assert np.all(np.mean(np.abs(settled) < 3.0 * mc["st_sigma"], axis=(0, 1)) > 0.99)
