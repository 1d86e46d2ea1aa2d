"""Tests of the HCW flight model (gnc.hcw) against independent references.

References: Vallado, *Fundamentals of Astrodynamics and Applications*,
Example 6-14 and the ``hillsv`` intercept; matrix exponentials and numerical
integration (scipy) of the HCW ODE written out independently here.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from scipy.integrate import quad_vec, solve_ivp
from scipy.linalg import expm

from gnc import constants
from gnc.hcw import (
    discretize,
    drift_per_orbit,
    hcw_matrices,
    hcw_stm,
    mean_motion,
    pro_state,
    process_noise,
    zoh_matrices,
)

# Vallado uses mu = 398600.4415 km^3/s^2 in Example 6-14.
MU_VALLADO = 398600.4415e9
N_590 = mean_motion(590e3, mu=MU_VALLADO, r_earth=6378136.3)
N_500 = mean_motion(500e3)


def _hcw_ode(n: float, u: np.ndarray | None = None) -> Callable[[float, np.ndarray], np.ndarray]:
    """HCW equations written out component-wise (independent of hcw_matrices)."""
    acc = np.zeros(3) if u is None else np.asarray(u, dtype=float)

    def rhs(_t: float, s: np.ndarray) -> np.ndarray:
        x, _y, z, vx, vy, vz = s
        return np.array(
            [
                vx,
                vy,
                vz,
                3.0 * n * n * x + 2.0 * n * vy + acc[0],
                -2.0 * n * vx + acc[1],
                -n * n * z + acc[2],
            ]
        )

    return rhs


def test_constants() -> None:
    assert constants.MU_EARTH_M3_S2 == 398600.4418e9
    assert constants.R_EARTH_M == 6378136.3
    assert constants.J2_EARTH == 1.08262668e-3


@pytest.mark.parametrize(
    ("alt_m", "n_ref"),
    [(400e3, 1.13137e-3), (500e3, 1.10678e-3), (600e3, 1.08308e-3)],
)
def test_mean_motion(alt_m: float, n_ref: float) -> None:
    assert mean_motion(alt_m) == pytest.approx(n_ref, abs=5e-9)


def test_vallado_example_6_14() -> None:
    s0 = np.array([0.0, 0.0, 0.0, -0.1, -0.04, -0.02])
    s = hcw_stm(N_590, 300.0) @ s0
    np.testing.assert_allclose(
        s[:3], [-33.345724432, -1.473560307, -5.894530312], rtol=0, atol=1e-6
    )
    np.testing.assert_allclose(s[3:], [-0.120337094, 0.032387584, -0.018949032], rtol=0, atol=1e-9)


def test_vallado_hillsv_intercept() -> None:
    r0 = np.array([-70.933, 20.357, -11.17])
    phi = hcw_stm(N_590, 300.0)
    v0 = -np.linalg.solve(phi[:3, 3:], phi[:3, :3] @ r0)
    np.testing.assert_allclose(v0, [0.274190838, 0.013466719, 0.035907981], rtol=0, atol=1e-9)
    # and the trajectory indeed reaches the origin
    np.testing.assert_allclose((phi @ np.concatenate([r0, v0]))[:3], 0.0, atol=1e-10)


def test_stm_identity_and_semigroup() -> None:
    np.testing.assert_array_equal(hcw_stm(N_500, 0.0), np.eye(6))
    t1, t2 = 1234.5, 3456.7
    np.testing.assert_allclose(
        hcw_stm(N_500, t1 + t2), hcw_stm(N_500, t2) @ hcw_stm(N_500, t1), rtol=1e-12, atol=1e-12
    )
    # inverse is the backward propagation; single terms of the product reach
    # ~1e4 (Phi_rv ~ 3 t), so its round-off is ~1e4 * 2.2e-16 ~ 2e-12
    np.testing.assert_allclose(
        hcw_stm(N_500, -t1) @ hcw_stm(N_500, t1), np.eye(6), rtol=0, atol=1e-10
    )


@pytest.mark.parametrize("t", [0.1, 10.0, 300.0, 2000.0, 5677.0])
def test_stm_equals_expm(t: float) -> None:
    a, _ = hcw_matrices(N_500)
    ref = expm(a * t)
    np.testing.assert_allclose(hcw_stm(N_500, t), ref, rtol=1e-11, atol=1e-11 * t)


def test_hcw_matrices_match_written_out_ode() -> None:
    a, b = hcw_matrices(N_500)
    rng = np.random.default_rng(1)
    for _ in range(5):
        s = rng.normal(size=6)
        u = rng.normal(size=3)
        np.testing.assert_allclose(a @ s + b @ u, _hcw_ode(N_500, u)(0.0, s), rtol=1e-15)


def test_stm_vectorised_over_time() -> None:
    ts = np.array([0.0, 10.0, 300.0])
    phis = hcw_stm(N_500, ts)
    assert phis.shape == (3, 6, 6)
    for k, t in enumerate(ts):
        np.testing.assert_array_equal(phis[k], hcw_stm(N_500, float(t)))


def test_one_time_gives_the_matrices_of_many_bit_for_bit() -> None:
    """One time is computed with Python floats (math.sin, math.cos), many with numpy's: the
    same operations in the same order, so the same bits as numpy gives for each shape of the
    time."""
    rng = np.random.default_rng(7)
    ts = np.r_[rng.uniform(0.0, 12000.0, 400), rng.uniform(0.0, 1.0, 50), 0.0, 1e-9, -30.0]
    phis, gams = zoh_matrices(N_500, ts)
    np.testing.assert_array_equal(phis, hcw_stm(N_500, ts))
    for k, t in enumerate(ts):
        for arg in (float(t), np.array(t), np.array([t]), np.array([[t]])):
            phi, gam = zoh_matrices(N_500, arg)
            assert phi.shape == np.shape(arg) + (6, 6) and gam.shape == np.shape(arg) + (6, 3)
            np.testing.assert_array_equal(phi.reshape(6, 6), phis[k])
            if np.ndim(arg) == 0:  # numpy squares a scalar with pow(), an array with x·x
                th = N_500 * np.float64(t)
                c1 = 2.0 * np.sin(0.5 * th) ** 2
                assert gam[0, 0] == c1 / N_500**2 and gam[4, 0] == -2.0 * c1 / N_500
                assert gam[1, 1] == (4.0 * c1 - 1.5 * th * th) / N_500**2
            else:
                np.testing.assert_array_equal(gam.reshape(6, 3), gams[k])
    with np.errstate(invalid="ignore"):  # no time: NaN, as numpy gives it, not an error
        assert np.isnan(zoh_matrices(N_500, np.inf)[1][0, 0])


def test_stm_matches_numerical_integration() -> None:
    s0 = np.array([120.0, -40.0, 35.0, 0.05, -0.21, 0.03])
    t_end = 4000.0
    sol = solve_ivp(_hcw_ode(N_500), (0.0, t_end), s0, method="DOP853", rtol=1e-12, atol=1e-12)
    s_num = sol.y[:, -1]
    s_cf = hcw_stm(N_500, t_end) @ s0
    assert np.max(np.abs(s_cf - s_num)) / np.max(np.abs(s_num)) < 1e-9


def test_discretize() -> None:
    dt = 10.0
    ad, bd = discretize(N_500, dt)
    np.testing.assert_allclose(ad, hcw_stm(N_500, dt), rtol=1e-12, atol=1e-14)
    # Bd column j = response at dt to a unit acceleration on axis j from rest.
    for j in range(3):
        u = np.zeros(3)
        u[j] = 1.0
        sol = solve_ivp(
            _hcw_ode(N_500, u), (0.0, dt), np.zeros(6), method="DOP853", rtol=1e-13, atol=1e-15
        )
        np.testing.assert_allclose(bd[:, j], sol.y[:, -1], rtol=1e-10, atol=1e-13)
    # small n*dt: double integrator, Bd ~ [dt^2/2 I; dt I] up to O(n dt) relative
    _, bd_small = discretize(N_500, 0.1)
    np.testing.assert_allclose(bd_small[:3], 0.005 * np.eye(3), rtol=0, atol=1e-3 * 0.005)
    np.testing.assert_allclose(bd_small[3:], 0.1 * np.eye(3), rtol=0, atol=1e-3 * 0.1)


@pytest.mark.parametrize("dt", [0.1, 1.0, 60.0, 600.0])
def test_process_noise_symmetric_psd(dt: float) -> None:
    q = 1e-10
    qd = process_noise(N_500, dt, q)
    np.testing.assert_array_equal(qd, qd.T)
    eig = np.linalg.eigvalsh(qd)
    assert eig.min() >= -1e-12 * eig.max()
    # independent quadrature of int_0^dt Phi(s) B B^T Phi(s)^T ds (closed-form Phi)
    _, b = hcw_matrices(N_500)

    def integrand(s: float) -> np.ndarray:
        g = hcw_stm(N_500, s) @ b
        return q * (g @ g.T)

    ref, _ = quad_vec(integrand, 0.0, dt, epsabs=0.0, epsrel=1e-12)
    np.testing.assert_allclose(qd, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())


def test_process_noise_small_dt_limit() -> None:
    q, dt = 2.5e-9, 0.1
    qd = process_noise(N_500, dt, q)
    for i in range(3):
        assert qd[i, i] == pytest.approx(q * dt**3 / 3.0, rel=1e-6)
        assert qd[i + 3, i + 3] == pytest.approx(q * dt, rel=1e-6)
        assert qd[i, i + 3] == pytest.approx(q * dt**2 / 2.0, rel=1e-6)
    np.testing.assert_array_equal(process_noise(N_500, dt, 0.0), np.zeros((6, 6)))


def test_bounded_condition_example() -> None:
    # 500 km, x0 = 100 m -> vy0 = -2 n x0 = -0.2213567 m/s (REFERENCE.md)
    s = pro_state(N_500, rho_x=100.0, alpha_x=math.pi / 2, rho_y=0.0, rho_z=0.0, alpha_z=0.0)
    assert s[0] == pytest.approx(100.0, abs=1e-12)
    assert s[4] == pytest.approx(-0.2213567, abs=5e-8)
    assert drift_per_orbit(N_500, s) == pytest.approx(0.0, abs=1e-12)


def test_pro_state_is_hcw_solution_and_periodic() -> None:
    args = dict(rho_x=50.0, alpha_x=0.3, rho_y=-20.0, rho_z=40.0, alpha_z=1.1)
    s0 = pro_state(N_500, **args)
    period = 2.0 * math.pi / N_500
    s1 = hcw_stm(N_500, period) @ s0
    np.testing.assert_allclose(s1, s0, rtol=0, atol=1e-12 * 100.0)
    assert drift_per_orbit(N_500, s0) == pytest.approx(0.0, abs=1e-10)
    # pro_state(t) equals propagation of pro_state(0) by Phi(t)
    for t in (100.0, 1000.0, 3333.3):
        np.testing.assert_allclose(
            pro_state(N_500, t=t, **args), hcw_stm(N_500, t) @ s0, rtol=0, atol=1e-11
        )
    # vy = -2 n x at all times
    st = pro_state(N_500, t=777.0, **args)
    assert st[4] == pytest.approx(-2.0 * N_500 * st[0], abs=1e-15)


def test_drift_per_orbit_matches_propagation() -> None:
    s0 = np.array([30.0, 0.0, 0.0, 0.0, -0.05, 0.0])
    period = 2.0 * math.pi / N_500
    dy = (hcw_stm(N_500, period) @ s0)[1] - s0[1]
    assert drift_per_orbit(N_500, s0) == pytest.approx(dy, rel=1e-12)
    assert abs(dy) > 1.0  # a real drift, not a trivially small number


def test_invalid_inputs() -> None:
    with pytest.raises(ValueError):
        hcw_stm(0.0, 1.0)
    with pytest.raises(ValueError):
        process_noise(N_500, 0.0, 1.0)
    with pytest.raises(ValueError):
        drift_per_orbit(N_500, np.zeros(5))
