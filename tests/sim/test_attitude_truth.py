"""Tests of the truth rigid-body attitude model (sim.attitude) against independent references.

References: the closed-form torque-free motion of an axisymmetric body (Euler; e.g. Markley &
Crassidis 2014, §3.3.5.1 / Wie, *Space Vehicle Dynamics and Control*, §6.4), conservation of total
angular momentum with internal wheel torques, the closed-form spin-up under a constant principal-
axis torque, and a DOP853 (scipy) integration of the gyrostat written independently here with
rotation-matrix kinematics (Ṙ = R [ω×]) instead of quaternions.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from sim.attitude import AttitudeTruth

DT = 0.1


def _dcm(q: np.ndarray) -> np.ndarray:
    """R_eci_body from scalar-last quaternions (N, 4), written out (Hamilton, active)."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def _angle_between(r1: Rotation, r2: Rotation) -> np.ndarray:
    return np.asarray((r1.inv() * r2).magnitude())


def _random_spd(rng: np.random.Generator, n: int) -> np.ndarray:
    """Random full (non-diagonal) inertias with principal moments 0.05..0.2 kg m²."""
    rot = Rotation.random(n, random_state=rng).as_matrix()
    moments = rng.uniform(0.05, 0.2, size=(n, 3))
    return np.einsum("nij,nj,nkj->nik", rot, moments, rot)


def test_axisymmetric_torque_free_matches_closed_form() -> None:
    I_t, I_3 = 0.06, 0.10
    J = np.diag([I_t, I_t, I_3])
    w0 = np.array([0.04, -0.03, 0.25])
    r0 = Rotation.from_rotvec([0.3, -1.2, 0.7])
    truth = AttitudeTruth(r0.as_quat()[None], w0[None], J, np.zeros((1, 3)))
    H_eci = r0.apply(J @ w0)
    omega_p = np.linalg.norm(H_eci) / I_t  # precession rate about H
    sigma = (I_t - I_3) * w0[2] / I_t  # body spin relative to the precessing frame
    lam = -sigma  # body-frame rotation rate of (w1, w2)
    worst_w = worst_att = 0.0
    for k in range(1, 6001):
        truth.step(DT, np.zeros((1, 3)))
        if k % 500 == 0:
            t = k * DT
            w12 = (w0[0] + 1j * w0[1]) * np.exp(1j * lam * t)
            w_ref = np.array([w12.real, w12.imag, w0[2]])
            r_ref = (Rotation.from_rotvec(H_eci / np.linalg.norm(H_eci) * omega_p * t) * r0
                     * Rotation.from_rotvec([0.0, 0.0, sigma * t]))
            worst_w = max(worst_w, float(np.max(np.abs(truth.w[0] - w_ref))))
            worst_att = max(worst_att, float(_angle_between(truth.r_eci_body(), r_ref)[0]))
    # 600 s of 10 Hz RK4 at |w| ~ 0.4 rad/s (measured: 3.0e-9 rad/s and 3.8e-8 rad).
    assert worst_w < 1e-8
    assert worst_att < 2e-7


def test_total_angular_momentum_conserved_with_wheel_exchange() -> None:
    rng = np.random.default_rng(11)
    n = 4
    J = _random_spd(rng, n)
    q0 = Rotation.random(n, random_state=rng).as_quat()
    w0 = rng.normal(0.0, 0.05, size=(n, 3))
    h0 = rng.normal(0.0, 0.01, size=(n, 3))
    truth = AttitudeTruth(q0, w0, J, h0)
    H0 = np.einsum("nij,nj->ni", _dcm(truth.q), np.einsum("nij,nj->ni", J, w0) + h0)
    worst = 0.0
    torques = rng.normal(0.0, 2e-4, size=(10000, n, 3))
    for k, tau in enumerate(torques):  # 1000 s, a new random wheel torque every tick
        truth.step(DT, tau)
        if k % 10:
            continue
        H = np.einsum("nij,nj->ni", _dcm(truth.q), np.einsum("nij,nj->ni", J, truth.w) + truth.h)
        rel = np.linalg.norm(H - H0, axis=1) / np.linalg.norm(H0, axis=1)
        worst = max(worst, float(np.max(rel)))
    assert np.max(np.abs(truth.h - h0)) > 1e-3  # the wheels really exchanged momentum
    assert worst < 1e-9
    np.testing.assert_allclose(truth.angular_momentum_eci(), H0, rtol=0,
                               atol=1e-9 * np.abs(H0).max())


@pytest.mark.parametrize("external", [False, True])
def test_constant_torque_spin_up_about_principal_axis(external: bool) -> None:
    J = np.diag([0.08, 0.12, 0.05])
    tau = 2e-3
    torque = np.array([[0.0, tau, 0.0]])
    r0 = Rotation.from_rotvec([0.2, 0.1, -0.4])
    truth = AttitudeTruth(r0.as_quat()[None], np.zeros((1, 3)), J, np.zeros((1, 3)))
    steps = 300
    for k in range(steps):
        t0 = k * DT
        if external:
            truth.step(DT, np.zeros((1, 3)), tau_ext_body=torque)
        else:
            truth.step(DT, torque)
        t1 = t0 + DT
        # mean rate over the step = ∫ τ t / J dt / dt
        expected = tau * (t1**2 - t0**2) / (2 * J[1, 1] * DT)
        np.testing.assert_allclose(truth.mean_rate[0, 1], expected, rtol=1e-12)
    t = steps * DT
    np.testing.assert_allclose(truth.w[0], [0.0, tau * t / J[1, 1], 0.0], rtol=0, atol=1e-13)
    h_ref = [0.0, 0.0, 0.0] if external else [0.0, -tau * t, 0.0]
    np.testing.assert_allclose(truth.h[0], h_ref, rtol=0, atol=1e-15)
    r_ref = r0 * Rotation.from_rotvec([0.0, tau * t**2 / (2 * J[1, 1]), 0.0])
    # 7.5 rad turned in 30 s by 10 Hz RK4 (measured 8.1e-9 rad).
    assert _angle_between(truth.r_eci_body(), r_ref)[0] < 5e-8


def _reference_gyrostat(J: np.ndarray, h: np.ndarray, r0: np.ndarray, w0: np.ndarray,
                        t_eval: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """DOP853 of J ω̇ = -ω × (J ω + h), Ṙ = R [ω×], constant wheel momentum h."""
    J_inv = np.linalg.inv(J)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        R = y[:9].reshape(3, 3)
        w = y[9:]
        wx = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
        return np.concatenate([(R @ wx).ravel(), J_inv @ (-np.cross(w, J @ w + h))])

    sol = solve_ivp(rhs, (0.0, t_eval[-1]), np.concatenate([r0.ravel(), w0]), method="DOP853",
                    rtol=1e-12, atol=1e-14, t_eval=t_eval)
    assert sol.success
    return sol.y[:9].T.reshape(-1, 3, 3), sol.y[9:].T


def test_free_asymmetric_gyrostat_matches_dop853() -> None:
    rng = np.random.default_rng(5)
    J = _random_spd(rng, 1)[0]
    h = np.array([0.004, -0.002, 0.003])
    w0 = np.array([0.15, -0.1, 0.2])
    r0 = Rotation.from_rotvec([0.5, 0.2, -0.9])
    t_end = 200.0
    t_eval = np.arange(0.0, t_end + 1e-9, 20.0)
    R_ref, w_ref = _reference_gyrostat(J, h, r0.as_matrix(), w0, t_eval)

    errors = {}
    for substeps in (1, 2):
        truth = AttitudeTruth(r0.as_quat()[None], w0[None], J, h[None])
        att_err = w_err = 0.0
        for k in range(1, int(round(t_end / DT)) + 1):
            truth.step(DT, np.zeros((1, 3)), substeps=substeps)
            if k % 200 == 0:
                i = k // 200
                dR = R_ref[i].T @ _dcm(truth.q)[0]
                att_err = max(att_err, float(Rotation.from_matrix(dR).magnitude()))
                w_err = max(w_err, float(np.max(np.abs(truth.w[0] - w_ref[i]))))
        errors[substeps] = (att_err, w_err)
    # 10 Hz RK4 at |w| <= 0.27 rad/s over 200 s (measured 1.5e-8 rad, 1.7e-10 rad/s) ...
    assert errors[1][0] < 5e-8 and errors[1][1] < 5e-9
    # ... and fourth order: halving the step divides the error by about 16.
    ratio = errors[1][0] / errors[2][0]
    assert 10.0 < ratio < 24.0


def test_quaternion_norm_and_vectorisation() -> None:
    rng = np.random.default_rng(2)
    n = 5
    J = _random_spd(rng, n)
    q0 = Rotation.random(n, random_state=rng).as_quat()
    w0 = rng.normal(0.0, 0.3, size=(n, 3))
    h0 = rng.normal(0.0, 0.01, size=(n, 3))
    torques = rng.normal(0.0, 1e-3, size=(200, n, 3))
    together = AttitudeTruth(q0, w0, J, h0)
    alone = [AttitudeTruth(q0[i], w0[i][None], J[i], h0[i][None]) for i in range(n)]
    for tau in torques:
        together.step(DT, tau)
        for i, a in enumerate(alone):
            a.step(DT, tau[i][None])
        assert np.max(np.abs(np.linalg.norm(together.q, axis=1) - 1.0)) < 1e-15
    for i, a in enumerate(alone):
        np.testing.assert_allclose(together.q[i], a.q[0], rtol=0, atol=1e-15)
        np.testing.assert_allclose(together.w[i], a.w[0], rtol=0, atol=1e-15)
    assert together.t_s == pytest.approx(200 * DT)


def test_bad_input_is_rejected() -> None:
    ok_q, ok_w, ok_h = np.array([[0.0, 0.0, 0.0, 1.0]]), np.zeros((1, 3)), np.zeros((1, 3))
    J = np.diag([1.0, 2.0, 3.0])
    with pytest.raises(ValueError):
        AttitudeTruth(np.zeros((1, 4)), ok_w, J, ok_h)
    with pytest.raises(ValueError):
        AttitudeTruth(ok_q, np.zeros((2, 3)), J, ok_h)
    with pytest.raises(ValueError):
        AttitudeTruth(ok_q, ok_w, np.diag([1.0, -2.0, 3.0]), ok_h)
    with pytest.raises(ValueError):
        AttitudeTruth(ok_q, ok_w, np.array([[1.0, 0.5, 0], [0.0, 1.0, 0], [0, 0, 1.0]]), ok_h)
    with pytest.raises(ValueError):
        AttitudeTruth(ok_q, np.array([[np.nan, 0.0, 0.0]]), J, ok_h)
    truth = AttitudeTruth(ok_q, ok_w, J, ok_h)
    with pytest.raises(ValueError):
        truth.step(DT, np.array([[np.nan, 0.0, 0.0]]))
    with pytest.raises(ValueError):
        truth.step(DT, np.zeros((2, 3)))
    with pytest.raises(ValueError):
        truth.step(0.0, ok_w)
    with pytest.raises(ValueError):
        truth.step(DT, ok_w, substeps=0)
    np.testing.assert_array_equal(truth.q, ok_q)  # a rejected step leaves the state alone
