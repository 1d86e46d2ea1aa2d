"""Tests of the SCP transfer planner (fsw.lib.scp) against independent references.

References: the same L1 problem (no keep-out) built here from the closed-form STM and a
numerically integrated input matrix and solved by scipy.optimize.linprog (HiGHS); the HCW ODE
integrated by scipy solve_ivp with the plan's held inputs (for the exact inter-node motion and the
keep-out check); the same problem on a 4x finer grid (for the discretisation gap).
Numbers: 500 km, 20-100 m transfers in 600-1500 s, u_max = 1e-3 m/s^2, N = 30-120.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from scipy.integrate import quad_vec, solve_ivp
from scipy.optimize import linprog

from fsw.lib.scp import (
    STATUS_INFEASIBLE_ENDPOINT,
    STATUS_INFEASIBLE_THRUST,
    STATUS_SOLVED,
    TransferPlan,
    plan_transfer,
    zoh_matrices,
)
from gnc.constants import R_EARTH_M
from gnc.hcw import discretize, hcw_stm, mean_motion
from gnc.pro import Pro, energy_matched_state

N_500 = mean_motion(500e3)
U_MAX = 1e-3
D_MIN = 10.0


def _hcw_rhs(n: float, u: np.ndarray) -> Callable[[float, np.ndarray], np.ndarray]:
    """HCW equations written out component-wise, with a constant acceleration u."""
    def rhs(_t: float, s: np.ndarray) -> np.ndarray:
        x, _y, z, vx, vy, vz = s
        return np.array([vx, vy, vz, 3 * n * n * x + 2 * n * vy + u[0], -2 * n * vx + u[1],
                         -n * n * z + u[2]])
    return rhs


def _integrate_plan(plan: TransferPlan, n: float,
                    per_interval: int) -> tuple[np.ndarray, np.ndarray]:
    """Independent truth: integrate the HCW ODE interval by interval from x0 with the plan's
    held inputs.  Returns (times, states) on a grid of per_interval points per interval."""
    h = float(plan.t_s[1] - plan.t_s[0])
    s = plan.x[0].copy()
    ts, xs = [], []
    for k, u in enumerate(plan.u):
        t_eval = np.linspace(0.0, h, per_interval + 1)
        sol = solve_ivp(_hcw_rhs(n, u), (0.0, h), s, method="DOP853", rtol=1e-11, atol=1e-12,
                        t_eval=t_eval)
        ts.append(k * h + sol.t[:-1])
        xs.append(sol.y.T[:-1])
        s = sol.y[:, -1]
    ts.append(np.array([plan.t_s[-1]]))
    xs.append(s[None, :])
    return np.concatenate(ts), np.concatenate(xs)


def _check_plan_feasible(plan: TransferPlan, x0: np.ndarray, xf: np.ndarray,
                         duration: float, n_int: int) -> None:
    assert plan.t_s.shape == (n_int + 1,) and plan.x.shape == (n_int + 1, 6)
    assert plan.u.shape == (n_int, 3)
    assert plan.t_s[-1] == pytest.approx(duration)
    assert np.max(np.abs(plan.u)) <= U_MAX * (1 + 1e-12)
    np.testing.assert_allclose(plan.x[0], x0, atol=1e-12)
    assert np.max(np.abs(plan.x[-1, :3] - xf[:3])) < 1e-6
    assert np.max(np.abs(plan.x[-1, 3:] - xf[3:])) < 1e-8
    h = duration / n_int
    assert plan.dv_mps == pytest.approx(np.sum(np.abs(plan.u)) * h, rel=1e-12)


def test_zoh_matrices_equal_the_matrix_exponential() -> None:
    for tau in (1e-3, 0.7, 10.0, 30.0, 600.0, 3000.0):
        ad, bd = discretize(N_500, tau)
        phi, gam = zoh_matrices(N_500, tau)
        np.testing.assert_allclose(phi, ad, rtol=0, atol=1e-10 * np.abs(ad).max())
        np.testing.assert_allclose(gam, bd, rtol=0, atol=1e-11 * np.abs(bd).max())
    phi, gam = zoh_matrices(N_500, np.array([5.0, 50.0]))
    assert phi.shape == (2, 6, 6) and gam.shape == (2, 6, 3)


def _linprog_reference(n: float, x0: np.ndarray, xf: np.ndarray, duration: float,
                       n_int: int, u_max: float) -> float:
    """The no-keep-out L1 problem condensed onto the inputs, built from hcw_stm and a
    quadrature of its velocity columns (Gamma(h) = int_0^h Phi(s) B ds), solved by HiGHS."""
    h = duration / n_int
    gam, _ = quad_vec(lambda s: hcw_stm(n, s)[:, 3:], 0.0, h, epsabs=1e-14, epsrel=1e-13)
    # x_N = Phi(T) x0 + sum_k Phi(T - (k+1) h) Gamma(h) u_k ;  u = u_plus - u_minus
    blocks = [hcw_stm(n, duration - (k + 1) * h) @ gam for k in range(n_int)]
    m = np.concatenate(blocks, axis=1)
    a_eq = np.concatenate([m, -m], axis=1)
    b_eq = xf - hcw_stm(n, duration) @ x0
    cost = np.full(6 * n_int, h)
    res = linprog(cost, A_eq=a_eq, b_eq=b_eq, bounds=(0.0, u_max), method="highs")
    assert res.status == 0, res.message
    return float(res.fun)


@pytest.mark.parametrize(
    ("x0", "xf", "duration", "n_int"),
    [
        (np.array([0.0, -40.0, 0.0, 0.0, 0.0, 0.0]), np.array([0.0, 40.0, 0.0, 0.0, 0.0, 0.0]),
         1200.0, 40),
        (Pro(20.0, 0.3, -30.0, 15.0, 1.0).state(N_500, 0.0),
         Pro(25.0, 2.0, 10.0, 30.0, -0.5).state(N_500, 900.0), 900.0, 30),
        (np.array([-25.0, 5.0, 10.0, 0.01, -0.02, 0.0]),
         np.array([30.0, -60.0, -5.0, 0.0, 0.0, 0.0]), 1500.0, 60),
    ],
)
def test_without_keep_out_matches_linprog(x0: np.ndarray, xf: np.ndarray, duration: float,
                                          n_int: int) -> None:
    plan = plan_transfer(N_500, x0, xf, duration, n_int, U_MAX)
    assert plan.status == STATUS_SOLVED and plan.converged and plan.iterations == 1
    _check_plan_feasible(plan, x0, xf, duration, n_int)
    ref = _linprog_reference(N_500, x0, xf, duration, n_int, U_MAX)
    assert plan.dv_mps == pytest.approx(ref, rel=1e-4)
    # nodes follow the ODE under the held inputs; state_at follows it between nodes
    t, truth = _integrate_plan(plan, N_500, 4)
    np.testing.assert_allclose(truth[::4], plan.x, atol=1e-7)
    np.testing.assert_allclose(plan.states_at(t), truth, atol=1e-7)
    i = 4 * (n_int // 3) + 3  # three quarters into an interval
    np.testing.assert_allclose(plan.state_at(float(t[i])), truth[i], atol=1e-7)


def _min_range_independent(plan: TransferPlan) -> tuple[float, float]:
    """(min over nodes, min over 50 points per interval) of |r|, from the ODE integration."""
    t, truth = _integrate_plan(plan, N_500, 50)
    nodes = float(np.min(np.linalg.norm(plan.x[:, :3], axis=1)))
    return nodes, float(np.min(np.linalg.norm(truth[:, :3], axis=1)))


@pytest.mark.parametrize(
    ("x0", "xf", "duration", "n_int"),
    [
        # cross-track through the centre: the unconstrained plan passes exactly through the
        # target (degenerate linearisation)
        (np.array([0.0, 0.0, -30.0, 0.0, 0.0, 0.0]), np.array([0.0, 0.0, 30.0, 0.0, 0.0, 0.0]),
         1200.0, 40),
        # slightly offset: the straight-ish path misses the centre by ~0.3 m
        (np.array([2.0, 1.0, -30.0, 0.0, 0.0, 0.0]), np.array([-2.0, 1.0, 30.0, 0.0, 0.0, 0.0]),
         1200.0, 30),
        # PRO to PRO across the target, terminal state energy matched
        (Pro(12.0, 0.0, -35.0, 12.0, 0.0).state(N_500, 0.0),
         energy_matched_state(Pro(12.0, math.pi, 35.0, 12.0, math.pi).state(N_500, 900.0),
                              R_EARTH_M + 500e3), 900.0, 50),
    ],
)
def test_keep_out_holds_at_nodes_and_along_the_exact_propagation(
        x0: np.ndarray, xf: np.ndarray, duration: float, n_int: int) -> None:
    free = plan_transfer(N_500, x0, xf, duration, n_int, U_MAX)
    assert free.converged and free.min_range_m < D_MIN - 1.0  # the keep-out is really needed
    plan = plan_transfer(N_500, x0, xf, duration, n_int, U_MAX, D_MIN)
    assert plan.status == STATUS_SOLVED and plan.converged
    _check_plan_feasible(plan, x0, xf, duration, n_int)
    nodes, dense = _min_range_independent(plan)
    assert nodes >= D_MIN - 1e-6
    assert dense >= D_MIN - 1e-6
    assert plan.min_range_m >= D_MIN
    assert plan.min_range_m <= dense + 1e-6  # the module's own check is at least as strict
    assert plan.dv_mps > free.dv_mps  # going around costs fuel


def test_keep_out_fuel_is_close_to_a_fine_grid_solve() -> None:
    x0 = np.array([2.0, 1.0, -30.0, 0.0, 0.0, 0.0])
    xf = np.array([-2.0, 1.0, 30.0, 0.0, 0.0, 0.0])
    coarse = plan_transfer(N_500, x0, xf, 1200.0, 30, U_MAX, D_MIN)
    fine = plan_transfer(N_500, x0, xf, 1200.0, 120, U_MAX, D_MIN)
    assert coarse.converged and fine.converged
    # a coarser ZOH grid can only restrict the thrust profile (up to the SCP's local optimum)
    assert coarse.dv_mps == pytest.approx(fine.dv_mps, rel=0.03)
    assert coarse.dv_mps >= fine.dv_mps * (1 - 1e-3)


def test_keep_out_already_met_gives_the_unconstrained_plan() -> None:
    x0 = np.array([0.0, -40.0, 0.0, 0.0, 0.0, 0.0])
    xf = np.array([0.0, 40.0, 0.0, 0.0, 0.0, 0.0])
    free = plan_transfer(N_500, x0, xf, 1200.0, 40, U_MAX)
    assert free.min_range_m > D_MIN
    plan = plan_transfer(N_500, x0, xf, 1200.0, 40, U_MAX, D_MIN)
    assert plan.converged and plan.iterations == 1
    np.testing.assert_allclose(plan.u, free.u, atol=1e-12)


def test_unreachable_terminal_state_reports_infeasible_thrust_limit() -> None:
    x0 = np.array([0.0, -40.0, 0.0, 0.0, 0.0, 0.0])
    xf = np.array([0.0, 40.0, 0.0, 0.0, 0.0, 0.0])
    for d_min in (None, D_MIN):
        plan = plan_transfer(N_500, x0, xf, 600.0, 40, 1e-5, d_min)
        assert plan.status == STATUS_INFEASIBLE_THRUST
        assert not plan.converged
        assert plan.u.shape == (40, 3) and not np.any(plan.u)  # well-formed, no thrust
    # the same transfer is fine with a realistic thrust limit
    assert plan_transfer(N_500, x0, xf, 600.0, 40, U_MAX).converged


def test_endpoint_inside_keep_out_is_a_status() -> None:
    x0 = np.array([0.0, -5.0, 0.0, 0.0, 0.0, 0.0])
    xf = np.array([0.0, 40.0, 0.0, 0.0, 0.0, 0.0])
    plan = plan_transfer(N_500, x0, xf, 600.0, 20, U_MAX, D_MIN)
    assert plan.status == STATUS_INFEASIBLE_ENDPOINT and not plan.converged


def test_bad_input_raises_value_error() -> None:
    x0 = np.zeros(6)
    xf = np.array([0.0, 40.0, 0.0, 0.0, 0.0, 0.0])
    bad_calls = [
        dict(x0=np.full(6, np.nan)), dict(x0=np.zeros(5)), dict(duration_s=-1.0),
        dict(duration_s=float("inf")), dict(n_intervals=0), dict(u_max_mps2=0.0),
        dict(d_min_m=-1.0), dict(n=0.0),
    ]
    base = dict(n=N_500, x0=x0, xf=xf, duration_s=600.0, n_intervals=20, u_max_mps2=U_MAX)
    for override in bad_calls:
        with pytest.raises(ValueError):
            plan_transfer(**{**base, **override})  # type: ignore[arg-type]
    plan = plan_transfer(**base)  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        plan.state_at(700.0)
    np.testing.assert_allclose(plan.state_at(600.0), plan.x[-1], atol=1e-12)
