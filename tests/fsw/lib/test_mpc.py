"""Tests of the OSQP tracking MPC (fsw/lib/mpc.py) against independent truth.

Truth dynamics here do not use ``hcw.discretize`` (the matrix exponential the MPC is built on):
the closed loop is propagated with the closed-form STM ``hcw.hcw_stm`` and the ZOH input matrix
``∫_0^dt Φ(τ) B dτ`` by Gauss-Legendre quadrature of that STM, itself checked against
``scipy.integrate.solve_ivp`` of the HCW ODE.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import linprog

from fsw.lib.mpc import MpcConfig, MpcResult, MpcTracker
from gnc import hcw

FloatArray = npt.NDArray[np.float64]

N_500 = hcw.mean_motion(500e3)
DT = 10.0
H = 20
U_MAX = 1e-3
PERIOD = 2.0 * math.pi / N_500
PRO = (50.0, 0.3, 5.0, 60.0, 1.0)  # rho_x, alpha_x, rho_y, rho_z, alpha_z (m, rad)


def zoh_input_matrix(n: float, dt: float) -> FloatArray:
    """∫_0^dt Φ(τ) B dτ (6x3) by 8-point Gauss-Legendre quadrature of the closed-form STM."""
    nodes, weights = np.polynomial.legendre.leggauss(8)
    tau = 0.5 * dt * (nodes + 1.0)
    phis = hcw.hcw_stm(n, tau)  # (8, 6, 6); B selects the velocity columns
    return 0.5 * dt * np.einsum("k,kij->ij", weights, phis[:, :, 3:6])


class Truth:
    """Exact HCW propagation over one step with a ZOH acceleration (independent of the MPC
    model)."""

    def __init__(self, n: float, dt: float) -> None:
        self.phi = hcw.hcw_stm(n, dt)
        self.gam = zoh_input_matrix(n, dt)

    def step(self, x: FloatArray, u: FloatArray) -> FloatArray:
        return self.phi @ x + self.gam @ u


def pro_table(n: float, steps: int, dt: float = DT) -> FloatArray:
    """Reference states on the PRO at t = 0, dt, ..., steps*dt, shape (steps+1, 6)."""
    return np.array([hcw.pro_state(n, *PRO, t=k * dt) for k in range(steps + 1)])


def closed_loop(
    mpc: MpcTracker, truth: Truth, x0: FloatArray, ref: FloatArray, steps: int,
    disturbance: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray, list[MpcResult]]:
    """Run the MPC in closed loop; returns states (steps+1, 6), applied inputs (steps, 3),
    results."""
    h = mpc.horizon
    d = np.zeros(3) if disturbance is None else disturbance
    xs = np.empty((steps + 1, 6))
    us = np.empty((steps, 3))
    xs[0] = x0
    results = []
    for k in range(steps):
        r = mpc.solve(xs[k], ref[k:k + h + 1])
        results.append(r)
        us[k] = r.u0
        xs[k + 1] = truth.step(xs[k], r.u0 + d)
    return xs, us, results


def test_truth_propagator_matches_ode() -> None:
    """The test's own truth model agrees with a tight RK integration of the HCW ODE."""
    a, b = hcw.hcw_matrices(N_500)
    truth = Truth(N_500, DT)
    rng = np.random.default_rng(11)
    for _ in range(3):
        x = rng.normal(0.0, [30, 30, 30, 0.03, 0.03, 0.03])
        u = rng.uniform(-U_MAX, U_MAX, 3)
        sol = solve_ivp(lambda _t, s, u=u: a @ s + b @ u, (0.0, DT), x, rtol=1e-12, atol=1e-13,
                        method="DOP853")
        np.testing.assert_allclose(truth.step(x, u), sol.y[:, -1], rtol=1e-10, atol=1e-11)


def test_on_pro_no_disturbance_thrust_stays_zero() -> None:
    """Starting exactly on a natural PRO and tracking it: no Δv over 10 orbits, state stays on
    it."""
    steps = int(math.ceil(10 * PERIOD / DT))
    ref = pro_table(N_500, steps + H)
    mpc = MpcTracker(N_500, MpcConfig())
    xs, us, results = closed_loop(mpc, Truth(N_500, DT), ref[0], ref, steps)
    assert all(r.ok for r in results)
    total_dv = float(np.abs(us).sum() * DT)
    assert total_dv < 1e-9  # m/s over 10 orbits
    dev = np.abs(xs - ref[: steps + 1])
    assert dev[:, :3].max() < 1e-7  # m (round-off between pro_state and the STM)
    assert dev[:, 3:].max() < 1e-10  # m/s


@pytest.mark.parametrize(
    "offset",
    [
        np.array([2.0, 0.0, 0.0, 0.005, 0.0, 0.0]),
        np.array([0.0, 2.0, 0.0, 0.0, 0.0, 0.0]),
        np.array([1.2, -1.2, 1.0, -0.003, 0.003, 0.003]),
    ],
)
def test_converges_from_offset_within_limits(offset: FloatArray) -> None:
    """From a 2 m / 5 mm/s offset the closed loop under exact HCW dynamics reaches < 5 cm by
    t = 1200 s and stays there, never exceeding u_max on any axis.  Fuel: within 3x of the
    fuel-optimal open-loop correction (linear program) that nulls the error by the time the
    MPC got under 5 cm for good."""
    steps = 150  # 1500 s
    ref = pro_table(N_500, steps + H)
    mpc = MpcTracker(N_500, MpcConfig())
    truth = Truth(N_500, DT)
    xs, us, results = closed_loop(mpc, truth, ref[0] + offset, ref, steps)
    assert all(r.ok for r in results)
    assert np.abs(us).max() <= U_MAX
    err = np.linalg.norm(xs[:, :3] - ref[: steps + 1, :3], axis=1)
    t = np.arange(steps + 1) * DT
    assert err[0] > 1.0
    assert err[t >= 1200.0].max() < 0.05
    assert np.linalg.norm(xs[-1, 3:] - ref[steps, 3:]) < 1e-4  # m/s

    # Fuel-optimal open loop over the MPC's settling time: min Σ|u|dt s.t. zero error at the
    # end, |u_i| <= u_max.  Error dynamics equal the state dynamics (natural reference orbit).
    n_conv = int(np.nonzero(err >= 0.05)[0].max()) + 1
    gs = [truth.gam]
    for _ in range(n_conv - 1):
        gs.append(truth.phi @ gs[-1])
    g = np.hstack(gs[::-1])  # column block k: Φ^{N-1-k} Γ
    b_eq = -np.linalg.matrix_power(truth.phi, n_conv) @ offset
    lp = linprog(np.full(6 * n_conv, DT), A_eq=np.hstack([g, -g]), b_eq=b_eq,
                 bounds=(0.0, U_MAX), method="highs")
    assert lp.status == 0
    assert float(np.abs(us).sum() * DT) < 3.0 * lp.fun


def _batch_least_squares(
    a: FloatArray, b: FloatArray, x0: FloatArray, ref: FloatArray, u_ref: FloatArray,
    cfg: MpcConfig,
) -> FloatArray:
    """Unconstrained finite-horizon LQR by stacking the predictions: X = Sx x0 + Su U, minimise
    Σ (X - R)'Q̄(X - R) + r_quad dt² |U - U_ref|² (normal equations)."""
    h = cfg.horizon
    sx = np.vstack([np.linalg.matrix_power(a, k + 1) for k in range(h)])
    su = np.zeros((6 * h, 3 * h))
    for i in range(h):
        for j in range(i + 1):
            su[6 * i:6 * i + 6, 3 * j:3 * j + 3] = np.linalg.matrix_power(a, i - j) @ b
    qd = np.array([cfg.q_pos] * 3 + [cfg.q_vel] * 3)
    qbar = np.concatenate([qd] * (h - 1) + [cfg.q_terminal_scale * qd])
    rw = cfg.r_quad * cfg.dt_s**2
    lhs = su.T @ (qbar[:, None] * su) + rw * np.eye(3 * h)
    rhs = su.T @ (qbar * (ref[1:].ravel() - sx @ x0)) + rw * u_ref.ravel()
    return np.linalg.solve(lhs, rhs).reshape(h, 3)


def test_unconstrained_l2_matches_batch_lqr() -> None:
    """With limits that never bind and r_l1 = 0 the QP is a finite-horizon LQR: inputs equal the
    closed-form batch least-squares solution (numpy), including a feed-forward u_ref."""
    cfg = MpcConfig(u_max_mps2=1.0, r_l1=0.0, r_quad=3e3, eps_abs=1e-10, eps_rel=1e-10,
                    max_iter=100000, polish=True)
    truth = Truth(N_500, DT)
    rng = np.random.default_rng(5)
    mpc = MpcTracker(N_500, cfg)
    for _ in range(3):
        ref = pro_table(N_500, H)
        x0 = ref[0] + rng.normal(0.0, [2, 2, 2, 0.005, 0.005, 0.005])
        u_ref = rng.normal(0.0, 1e-3, (H, 3))
        res = mpc.solve(x0, ref, u_ref)
        assert res.ok, res.status
        u_ls = _batch_least_squares(truth.phi, truth.gam, x0, ref, u_ref, cfg)
        assert np.abs(u_ls).max() < 0.1 * cfg.u_max_mps2  # limits really inactive
        assert np.linalg.norm(res.u0 - u_ls[0]) <= 1e-5 * np.linalg.norm(u_ls[0])
        assert np.linalg.norm(res.u - u_ls) <= 1e-5 * np.linalg.norm(u_ls)
        # predicted states follow the exact dynamics under the returned inputs
        np.testing.assert_allclose(res.x_pred[0], x0, atol=1e-9)
        for k in range(H):
            np.testing.assert_allclose(res.x_pred[k + 1], truth.step(res.x_pred[k], res.u[k]),
                                       rtol=0, atol=1e-7)


def test_feedforward_plan_is_followed_at_no_extra_cost() -> None:
    """Reference made by a planned burn sequence: given the plan as u_ref, the MPC applies it
    exactly (Σ|u - u_ref| dt ≈ 0) and the state stays on the planned trajectory."""
    steps = 60
    truth = Truth(N_500, DT)
    rng = np.random.default_rng(8)
    plan = np.zeros((steps + H, 3))
    plan[:30] = rng.uniform(-0.6 * U_MAX, 0.6 * U_MAX, (30, 3))
    ref = np.empty((steps + H + 1, 6))
    ref[0] = hcw.pro_state(N_500, *PRO)
    for k in range(steps + H):
        ref[k + 1] = truth.step(ref[k], plan[k])
    mpc = MpcTracker(N_500, MpcConfig(polish=True))
    x = ref[0].copy()
    extra = 0.0
    for k in range(steps):
        r = mpc.solve(x, ref[k:k + H + 1], plan[k:k + H])
        assert r.ok
        extra += float(np.abs(r.u0 - plan[k]).sum() * DT)
        x = truth.step(x, r.u0)
    planned_dv = float(np.abs(plan).sum() * DT)
    assert planned_dv > 0.05
    assert extra < 1e-7 * planned_dv
    assert np.abs(x - ref[steps]).max() < 1e-6


def test_bounded_error_under_unknown_constant_disturbance() -> None:
    """A constant unmodelled acceleration (1e-6 m/s² class): tracking error stays bounded
    (< 5 cm over 2 orbits) whereas open loop it drifts by tens of metres."""
    steps = int(math.ceil(2 * PERIOD / DT))
    ref = pro_table(N_500, steps + H)
    dist = np.array([3e-7, 1e-6, -5e-7])
    truth = Truth(N_500, DT)
    xs, us, results = closed_loop(MpcTracker(N_500), truth, ref[0], ref, steps, dist)
    assert all(r.ok for r in results)
    err = np.linalg.norm(xs[:, :3] - ref[: steps + 1, :3], axis=1)
    assert err.max() < 0.05
    # the same disturbance without control
    x = ref[0].copy()
    for _ in range(steps):
        x = truth.step(x, dist)
    assert np.linalg.norm(x[:3] - ref[steps, :3]) > 10.0
    # the controller spends about what the disturbance imparts, not orders of magnitude more
    assert float(np.abs(us).sum() * DT) < 3.0 * float(np.abs(dist).sum() * steps * DT)


def test_warm_start_saves_iterations_and_reset_drops_it() -> None:
    """Warm-started steps need fewer OSQP iterations than the same steps started cold."""
    steps = 80
    ref = pro_table(N_500, steps + H)
    truth = Truth(N_500, DT)
    rng = np.random.default_rng(2)
    noise = rng.normal(0.0, 1e-5, (steps, 3))
    iters: dict[bool, list[int]] = {True: [], False: []}
    for warm in (True, False):
        mpc = MpcTracker(N_500)
        x = ref[0] + np.array([1.0, 0.5, -0.5, 0.001, 0.0, 0.002])
        for k in range(steps):
            if not warm:
                mpc.reset()
            r = mpc.solve(x, ref[k:k + H + 1])
            assert r.ok
            iters[warm].append(r.iterations)
            x = truth.step(x, r.u0) + np.concatenate([np.zeros(3), noise[k]])
    assert np.mean(iters[True]) < 0.7 * np.mean(iters[False])


def test_bad_inputs_raise_value_error() -> None:
    mpc = MpcTracker(N_500)
    ref = pro_table(N_500, H)
    x0 = ref[0].copy()
    bad_x0 = x0.copy()
    bad_x0[2] = np.nan
    bad_ref = ref.copy()
    bad_ref[4, 1] = np.inf
    with pytest.raises(ValueError):
        mpc.solve(bad_x0, ref)
    with pytest.raises(ValueError):
        mpc.solve(x0, bad_ref)
    with pytest.raises(ValueError):
        mpc.solve(x0[:5], ref)
    with pytest.raises(ValueError):
        mpc.solve(x0, ref[:-1])
    with pytest.raises(ValueError):
        mpc.solve(x0, ref, np.zeros((H, 2)))
    with pytest.raises(ValueError):
        mpc.solve(x0, ref, np.full((H, 3), np.nan))
    with pytest.raises(ValueError):
        mpc.solve(x0, [["a"] * 6] * (H + 1))
    # after rejected calls the tracker still works
    assert mpc.solve(x0, ref).ok


@pytest.mark.parametrize(
    "kwargs",
    [{"dt_s": 0.0}, {"horizon": 0}, {"horizon": 2.5}, {"u_max_mps2": -1e-3},
     {"u_max_mps2": math.inf}, {"q_pos": math.nan}, {"r_l1": -1.0}, {"max_iter": 0},
     {"eps_abs": 0.0}],
)
def test_bad_config_raises(kwargs: dict[str, float]) -> None:
    with pytest.raises(ValueError):
        MpcConfig(**kwargs)  # type: ignore[arg-type]


def test_impossible_reference_reports_and_saturates() -> None:
    """A reference that jumps 1 km along-track cannot be reached in 200 s with 1e-3 m/s²: the
    solve does not raise, the first input saturates toward it, and the predicted miss is large."""
    mpc = MpcTracker(N_500)
    ref = pro_table(N_500, H)
    far = ref.copy()
    far[3:, 1] += 1000.0
    res = mpc.solve(ref[0], far)
    assert isinstance(res.status, str)
    assert res.ok, res.status
    assert np.abs(res.u0).max() <= U_MAX
    assert res.u0[1] == pytest.approx(U_MAX, rel=1e-6)
    assert np.linalg.norm(res.x_pred[-1, :3] - far[-1, :3]) > 900.0


def test_solver_failure_is_reported_not_raised() -> None:
    """An iteration cap too small to converge: ok False, status reported, zero command, free
    prediction; the next solve starts cold and the tracker is still usable."""
    mpc = MpcTracker(N_500, MpcConfig(max_iter=1))
    ref = pro_table(N_500, H)
    x0 = ref[0] + np.array([1.0, 0, 0, 0, 0.002, 0])
    res = mpc.solve(x0, ref)
    assert not res.ok
    assert res.status == "maximum iterations reached"
    np.testing.assert_array_equal(res.u0, np.zeros(3))
    np.testing.assert_array_equal(res.u, np.zeros((H, 3)))
    truth = Truth(N_500, DT)
    np.testing.assert_allclose(res.x_pred[-1], np.linalg.matrix_power(truth.phi, H) @ x0, atol=1e-8)
