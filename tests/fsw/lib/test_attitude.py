"""Tests of attitude guidance (fsw.lib.attitude) and control (fsw.lib.attitude_control).

Independent truth used here:

* the rigid body with reaction wheels, ``J ω̇ = −ω × (J ω + h) + τ``, ``ḣ = −τ``,
  ``q̇ = ½ q ⊗ (ω, 0)``, written out in this file and integrated with
  scipy.integrate.solve_ivp (controller at 10 Hz, torque held constant in between);
* closed forms: geodesic angles, the best achievable secondary-axis error of a
  pointing, the second-order step response, the Lyapunov function of the
  quaternion-feedback law and its exact dissipation ``V̇ = −kd |ω_e|²``;
* an independent solver (scipy.optimize.minimize, SLSQP) for the one-axis slew,
  where the kinematics is exactly linear;
* the kinematic bound ``θ ≤ ∫|ω| dt ≤ √3 w_max T`` for the infeasible slew.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from fsw.lib.attitude import SlewPlan, pointing_rotation, scp_slew, slerp_plan
from fsw.lib.attitude_control import AttitudeGains, gains_for, tracking_torque

J_DIAG = np.diag([0.10, 0.12, 0.08])
J_FULL = np.array([[0.10, 0.006, -0.004], [0.006, 0.12, 0.003], [-0.004, 0.003, 0.08]])
TAU_MAX = 2e-3  # N·m per axis
H_MAX = 0.02  # N·m·s per axis
DT = 0.1  # controller period, s
N_ORBIT = 1.1e-3  # rad/s
DEG = math.pi / 180.0


# ---------------------------------------------------------------------------
# independent rigid-body model


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _qmul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product, scalar-last."""
    pv, pw = p[:3], p[3]
    qv, qw = q[:3], q[3]
    return np.concatenate([pw * qv + qw * pv + _cross(pv, qv), [pw * qw - pv @ qv]])


def _qdot(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """q̇ = ½ q ⊗ (ω, 0), written out."""
    x, y, z, s = q
    a, b, c = w
    return 0.5 * np.array([s * a + y * c - z * b, s * b + z * a - x * c, s * c + x * b - y * a,
                           -x * a - y * b - z * c])


def _body_rhs(j: np.ndarray, tau: np.ndarray) -> Callable[[float, np.ndarray], np.ndarray]:
    """State [q (4), ω (3), h (3)] with constant body torque tau."""
    j_inv = np.linalg.inv(j)
    out = np.empty(10)
    out[7:10] = -tau

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        w = y[4:7]
        out[0:4] = _qdot(y[0:4], w)
        out[4:7] = j_inv @ (tau - _cross(w, j @ w + y[7:10]))
        return out.copy()

    return rhs


@dataclass
class _Run:
    t: np.ndarray  # controller sample times, s
    q: np.ndarray  # attitude at the samples
    w: np.ndarray
    h: np.ndarray
    tau: np.ndarray  # torque applied on [t_k, t_k + DT)
    err: np.ndarray  # error angle reported by the controller, rad
    err_truth: np.ndarray  # error angle recomputed here, rad


def _simulate(
    j: np.ndarray,
    r0: Rotation,
    w0: np.ndarray,
    h0: np.ndarray,
    desired: Callable[[float], tuple[Rotation, np.ndarray, np.ndarray]],
    gains: AttitudeGains,
    t_end: float,
    tau_max: float = TAU_MAX,
) -> _Run:
    """Closed loop: controller at 1/DT Hz with zero-order-hold torque."""
    y = np.concatenate([r0.as_quat(), w0, h0])
    rows: dict[str, list[np.ndarray | float]] = {
        k: [] for k in ("t", "q", "w", "h", "tau", "e", "et")}
    steps = int(round(t_end / DT))
    for k in range(steps + 1):
        t = k * DT
        r = Rotation.from_quat(y[0:4])
        r_d, w_d, wdot_d = desired(t)
        tau, err = tracking_torque(r, y[4:7], r_d, w_d, wdot_d, j, y[7:10], gains, tau_max)
        for key, val in (("t", t), ("q", y[0:4].copy()), ("w", y[4:7].copy()),
                         ("h", y[7:10].copy()), ("tau", tau), ("e", err),
                         ("et", (r_d.inv() * r).magnitude())):
            rows[key].append(val)
        if k == steps:
            break
        sol = solve_ivp(_body_rhs(j, tau), (t, t + DT), y, method="DOP853", rtol=1e-10, atol=1e-12)
        assert sol.success
        y = sol.y[:, -1]
        y[0:4] /= np.linalg.norm(y[0:4])
    return _Run(*(np.array(rows[k]) for k in ("t", "q", "w", "h", "tau", "e", "et")))


def _hold(r: Rotation) -> Callable[[float], tuple[Rotation, np.ndarray, np.ndarray]]:
    return lambda _t: (r, np.zeros(3), np.zeros(3))


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    return math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b))


# ---------------------------------------------------------------------------
# pointing


def test_pointing_boresight_exact_and_secondary_optimal() -> None:
    rng = np.random.default_rng(11)
    for _ in range(20):
        los, up_r, bore, up_b = rng.normal(size=(4, 3))
        r = pointing_rotation(los * 37.0, boresight_body=bore, up_ref=up_r, up_body=up_b)
        bore_u = bore / np.linalg.norm(bore)
        np.testing.assert_allclose(r.apply(bore_u), los / np.linalg.norm(los), atol=1e-12)
        # the secondary body axis lies on a cone of half-angle β about the LOS; the
        # closest it can get to up_ref (at γ from the LOS) is |γ − β|
        beta = _angle(bore, up_b)
        gamma = _angle(los, up_r)
        assert _angle(r.apply(up_b), up_r) == pytest.approx(abs(gamma - beta), abs=1e-9)


def test_pointing_defaults_and_degenerate_secondary() -> None:
    # default boresight +z, default secondary body +y toward reference +z
    r = pointing_rotation([1.0, 0.0, 0.0])
    np.testing.assert_allclose(r.apply([0, 0, 1]), [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(r.apply([0, 1, 0]), [0, 0, 1], atol=1e-12)
    # up_ref parallel / antiparallel to the LOS: shortest-arc fallback
    for los in ([0.0, 0.0, 2.0], [0.3, 0.0, -5.0], [1e-9, 0.0, -1.0]):
        los_u = np.asarray(los) / np.linalg.norm(los)
        r = pointing_rotation(los, boresight_body=[1.0, 1.0, 0.0], up_ref=[0.0, 0.0, 1.0]
                              if abs(los_u[2]) > 0.999 else los)
        b = np.array([1.0, 1.0, 0.0]) / math.sqrt(2.0)
        np.testing.assert_allclose(r.apply(b), los_u, atol=1e-12)
        assert r.magnitude() == pytest.approx(_angle(b, los_u), abs=1e-9)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"los_ref": [0.0, 0.0, 0.0]},
        {"los_ref": [np.nan, 0.0, 1.0]},
        {"los_ref": [1.0, 0.0]},
        {"los_ref": [1.0, 0.0, 0.0], "up_body": [0.0, 0.0, -3.0]},
        {"los_ref": [1.0, 0.0, 0.0], "boresight_body": [0.0, 0.0, 0.0]},
    ],
)
def test_pointing_bad_input(kwargs: dict[str, object]) -> None:
    with pytest.raises(ValueError):
        pointing_rotation(**kwargs)  # type: ignore[arg-type]


# ---------------------------------------------------------------------------
# slerp


@pytest.mark.parametrize("flip", [False, True])
def test_slerp_plan_constant_rate_short_way(flip: bool) -> None:
    rng = np.random.default_rng(5)
    for _ in range(5):
        r0 = Rotation.random(random_state=rng)
        r1 = Rotation.random(random_state=rng)
        if flip:
            r1 = Rotation.from_quat(-r1.as_quat())
        theta = (r0.inv() * r1).magnitude()
        plan = slerp_plan(r0, r1, 10.0, 70.0)
        ts = np.linspace(10.0, 70.0, 121)
        rots = [plan.at(float(t))[0] for t in ts]
        for t, r in zip(ts, rots, strict=True):
            assert np.linalg.norm(r.as_quat()) == pytest.approx(1.0, abs=1e-12)
            assert (r0.inv() * r).magnitude() == pytest.approx(theta * (t - 10.0) / 60.0, abs=1e-9)
        travelled = sum((a.inv() * b).magnitude() for a, b in zip(rots[:-1], rots[1:], strict=True))
        assert travelled == pytest.approx(theta, abs=1e-9)
        assert travelled <= math.pi + 1e-12
        assert (rots[-1].inv() * r1).magnitude() < 1e-9
        # rate: finite difference of the attitude, body axes
        for t in (10.0, 33.3, 69.0):
            r_a, w, wdot = plan.at(t)
            r_b = plan.at(t + 1e-3)[0]
            np.testing.assert_allclose((r_a.inv() * r_b).as_rotvec() / 1e-3, w, atol=1e-9)
            np.testing.assert_array_equal(wdot, np.zeros(3))
        # clamped outside with zero rate
        for t, r_end in ((0.0, r0), (100.0, r1)):
            r, w, _ = plan.at(t)
            assert (r.inv() * r_end).magnitude() < 1e-12
            np.testing.assert_array_equal(w, np.zeros(3))


def test_slerp_plan_near_pi_takes_short_way() -> None:
    r0 = Rotation.identity()
    q1 = Rotation.from_rotvec([0.0, 0.0, 170.0 * DEG]).as_quat()
    for r1 in (Rotation.from_quat(q1), Rotation.from_quat(-q1)):
        plan = slerp_plan(r0, r1, 0.0, 17.0)
        assert plan.angle_rad == pytest.approx(170.0 * DEG, abs=1e-12)
        np.testing.assert_allclose(plan.at(8.5)[0].as_rotvec(), [0, 0, 85.0 * DEG], atol=1e-12)
    with pytest.raises(ValueError):
        slerp_plan(r0, r0, 5.0, 5.0)


# ---------------------------------------------------------------------------
# SCP slew


def _exact_landing(plan: SlewPlan, r0: Rotation) -> Rotation:
    """Integrate the planned piecewise-constant rates with the exact exponential map."""
    h = float(plan.t_s[1] - plan.t_s[0])
    r = r0
    for wk in plan.w:
        r = r * Rotation.from_rotvec(wk * h)
    return r


def test_scp_slew_90deg_rate_limited() -> None:
    r0 = Rotation.from_euler("xyz", [10.0, 20.0, 30.0], degrees=True)
    axis = np.array([1.0, 2.0, -1.0]) / math.sqrt(6.0)
    r1 = r0 * Rotation.from_rotvec(90.0 * DEG * axis)
    zero = np.zeros(3)
    # with a loose limit the smooth profile peaks above 0.03 rad/s on body y ...
    loose = scp_slew(r0, r1, 60.0, 31, 0.1, w0=zero, w1=zero)
    assert loose.status == "solved"
    assert np.max(np.abs(loose.w)) > 0.032
    # ... so a limit of 0.03 rad/s is active
    w_max = 0.03
    r1_neg = Rotation.from_quat(-r1.as_quat())  # the sign of r1 must not matter
    plan = scp_slew(r0, r1_neg, 60.0, 31, w_max, w0=zero, w1=zero)
    assert plan.status == "solved" and plan.converged
    assert plan.q.shape == (31, 4) and plan.w.shape == (30, 3)
    assert np.max(np.abs(plan.w)) <= w_max * (1.0 + 1e-12)
    assert np.max(np.abs(plan.w)) == pytest.approx(w_max, rel=1e-6)
    # boundary attitudes and rates
    assert (Rotation.from_quat(plan.q[0]).inv() * r0).magnitude() < 1e-9
    assert (Rotation.from_quat(plan.q[-1]).inv() * r1).magnitude() < 1e-9
    np.testing.assert_allclose(plan.w[[0, -1]], 0.0, atol=1e-12)
    # exact kinematics lands on r1 (stated tolerance 1e-6 rad)
    assert (_exact_landing(plan, r0).inv() * r1).magnitude() < 1e-6
    assert plan.terminal_error_rad < 1e-6
    # short way: total angle travelled by the rates is close to the geodesic 90°
    travelled = float(np.sum(np.linalg.norm(plan.w, axis=1)) * 2.0)
    assert 90.0 * DEG - 1e-9 <= travelled < 90.0 * DEG * 1.05
    # planned quaternions were unit before renormalisation (linearised norm constraint)
    assert plan.norm_error < 1e-3
    first = scp_slew(r0, r1, 60.0, 31, w_max, w0=zero, w1=zero, max_iters=1)
    assert first.norm_error < 1e-2  # even the first step from slerp (reported: ~3e-3)
    # at(): nodes and rates
    for k in (0, 7, 30):
        r, _, _ = plan.at(float(plan.t_s[k]))
        assert (r.inv() * Rotation.from_quat(plan.q[k])).magnitude() < 1e-12
    _, w_mid, wdot = plan.at(float(plan.t_s[7]) + 0.5)
    np.testing.assert_array_equal(w_mid, plan.w[7])
    np.testing.assert_array_equal(wdot, np.zeros(3))


def test_scp_slew_one_axis_matches_independent_qp() -> None:
    """About a fixed body axis the kinematics is linear; compare with SLSQP."""
    n, duration, w_max, theta = 20, 40.0, 0.05, 75.0 * DEG
    h = duration / n
    r0 = Rotation.from_rotvec([0.2, -0.1, 0.3])
    plan = scp_slew(r0, r0 * Rotation.from_rotvec([0.0, 0.0, theta]), duration, n + 1, w_max,
                    w0=np.zeros(3), w1=np.zeros(3))
    assert plan.status == "solved"
    np.testing.assert_allclose(plan.w[:, :2], 0.0, atol=1e-7)

    # cost of scp_slew on u = ω/w_max: N Σ(Δu)² + (0.01/N) Σu², s.t. Σ u h w_max = θ
    def cost(u: np.ndarray) -> float:
        return float(n * np.sum(np.diff(u) ** 2) + 0.01 / n * np.sum(u**2))

    cons = [{"type": "eq", "fun": lambda u: np.sum(u) * h * w_max - theta}]
    bounds = [(0.0, 0.0)] + [(-1.0, 1.0)] * (n - 2) + [(0.0, 0.0)]
    ref = minimize(cost, np.full(n, 0.5), method="SLSQP", bounds=bounds, constraints=cons,
                   options={"ftol": 1e-14, "maxiter": 500})
    assert ref.success
    np.testing.assert_allclose(plan.w[:, 2] / w_max, ref.x, atol=1e-5)


def test_scp_slew_nonzero_boundary_rates() -> None:
    r0 = Rotation.identity()
    r1 = Rotation.from_rotvec([0.3, 0.2, -0.4])
    w0 = np.array([0.01, 0.0, 0.02])
    w1 = np.array([0.0, 0.01, 0.0])
    plan = scp_slew(r0, r1, 30.0, 21, 0.05, w0=w0, w1=w1, t0_s=100.0)
    assert plan.status == "solved"
    np.testing.assert_allclose(plan.w[0], w0, atol=1e-12)
    np.testing.assert_allclose(plan.w[-1], w1, atol=1e-12)
    assert plan.t_s[0] == 100.0 and plan.t_s[-1] == pytest.approx(130.0)
    assert (_exact_landing(plan, r0).inv() * r1).magnitude() < 1e-6


def test_scp_slew_infeasible_reported() -> None:
    # any path needs θ ≤ ∫|ω| dt ≤ √3 w_max T: 90° in 60 s is impossible at 0.014 rad/s
    w_max, duration, theta = 0.014, 60.0, 90.0 * DEG
    assert math.sqrt(3.0) * w_max * duration < theta
    plan = scp_slew(Rotation.identity(), Rotation.from_rotvec([theta, 0.0, 0.0]), duration, 31,
                    w_max, w0=np.zeros(3), w1=np.zeros(3))
    assert plan.status == "infeasible" and not plan.converged
    # a boundary rate above the limit (e.g. a measured rate) cannot be met either
    plan = scp_slew(Rotation.identity(), Rotation.from_rotvec([0.1, 0.0, 0.0]), 30.0, 11, 0.05,
                    w0=[0.0, 0.06, 0.0])
    assert plan.status == "infeasible" and plan.iterations == 0


@pytest.mark.parametrize(
    "kwargs",
    [
        {"n_nodes": 2},
        {"duration_s": 0.0},
        {"duration_s": math.nan},
        {"w_max_radps": -1.0},
        {"w1": [0.0, np.nan, 0.0]},
        {"w0": [0.0, 0.0]},
        {"max_iters": 0},
    ],
)
def test_scp_slew_bad_input(kwargs: dict[str, object]) -> None:
    args: dict[str, object] = {"duration_s": 10.0, "n_nodes": 11, "w_max_radps": 0.1}
    args.update(kwargs)
    with pytest.raises(ValueError):
        scp_slew(Rotation.identity(), Rotation.from_rotvec([0.1, 0, 0]), **args)  # type: ignore[arg-type]


# ---------------------------------------------------------------------------
# controller


def test_gains_for_small_error_response_is_the_designed_second_order() -> None:
    ts, zeta = 20.0, 0.9
    g = AttitudeGains.gains_for(ts, zeta)
    wn = 4.0 / (zeta * ts)
    assert g.natural_frequency_radps == pytest.approx(wn) and g.damping == pytest.approx(zeta)
    assert gains_for(ts, zeta, 0.05) == AttitudeGains.gains_for(ts, zeta, w_max_radps=0.05)
    # 0.5° error at rest about a principal axis, no limits: θ(t) of θ̈ + 2ζωnθ̇ + ωn²θ = 0
    th0 = 0.5 * DEG
    run = _simulate(J_DIAG, Rotation.from_rotvec([th0, 0.0, 0.0]), np.zeros(3), np.zeros(3),
                    _hold(Rotation.identity()), g, 40.0, tau_max=math.inf)
    sigma, wd = zeta * wn, wn * math.sqrt(1.0 - zeta**2)
    theta = th0 * np.exp(-sigma * run.t) * (np.cos(wd * run.t) + sigma / wd * np.sin(wd * run.t))
    assert np.max(np.abs(run.err_truth - np.abs(theta))) < 0.01 * th0
    np.testing.assert_allclose(run.err, run.err_truth, atol=1e-12)
    # overdamped design: slow pole at 4/ts
    g2 = AttitudeGains.gains_for(ts, 2.0)
    wn2 = g2.natural_frequency_radps
    assert g2.damping == pytest.approx(2.0)
    assert wn2 * (2.0 - math.sqrt(3.0)) == pytest.approx(4.0 / ts)


def _slew_settling_bound(g: AttitudeGains, j: np.ndarray, theta0: float, tol: float) -> float:
    """Time by which a rest-to-rest eigen-axis slew of theta0 is within tol (rad).

    Cruise at w_max while (kp/kd) sin(θ/2) > w_max, i.e. down to
    θ_sw = 2 asin(w_max kd / kp), after a build-up that costs at most
    1/kd (first-order rate loop) + w_max / (2 α) (torque-limited ramp at
    α ≥ τ_max / ‖J‖_∞); then the linear second-order decay from (θ_sw, −w_max)
    with envelope A e^{−ζ ω_n t}, A = sqrt(x0² + ((v0 + σ x0)/ω_d)²).
    """
    w_max = g.w_max_radps
    assert w_max is not None
    alpha = TAU_MAX / float(np.max(np.sum(np.abs(j), axis=1)))
    th_sw = 2.0 * math.asin(min(1.0, w_max * g.kd / g.kp))
    t_cruise = (theta0 - th_sw) / w_max + 1.0 / g.kd + w_max / (2.0 * alpha)
    wn, zeta = g.natural_frequency_radps, g.damping
    sigma, wd = zeta * wn, wn * math.sqrt(1.0 - zeta**2)
    amp = math.hypot(th_sw, (-w_max + sigma * th_sw) / wd)
    return t_cruise + math.log(amp / tol) / sigma


@pytest.mark.parametrize("j", [J_DIAG, J_FULL], ids=["diagonal", "full"])
def test_regulation_90deg_settles_within_limits(j: np.ndarray) -> None:
    w_max = 0.05
    g = AttitudeGains.gains_for(10.0, 0.9, w_max_radps=w_max)
    theta0, tol = 90.0 * DEG, 1.0 * DEG
    t_settle = _slew_settling_bound(g, j, theta0, tol)
    r_des = Rotation.from_euler("zyx", [40.0, -10.0, 5.0], degrees=True)
    axis = np.array([0.6, -0.48, 0.64])
    r0 = r_des * Rotation.from_rotvec(theta0 * axis)
    run = _simulate(j, r0, np.zeros(3), np.zeros(3), _hold(r_des), g, t_settle + 15.0)
    assert run.err_truth[0] == pytest.approx(theta0)
    np.testing.assert_allclose(run.err, run.err_truth, atol=1e-9)
    after = run.t >= t_settle
    assert np.all(run.err_truth[after] < tol)
    assert np.all(np.abs(run.tau) <= TAU_MAX * (1.0 + 1e-12))
    assert np.max(np.abs(run.tau)) == pytest.approx(TAU_MAX)  # the torque limit was reached
    assert np.all(np.abs(run.h) <= H_MAX)
    # rate-limited mode: the slew rate never exceeds w_max (1 % for ZOH/gyroscopics) ...
    assert np.max(np.linalg.norm(run.w, axis=1)) <= 1.01 * w_max
    # ... so the error cannot shrink faster than w_max allows
    t_cross = run.t[np.argmax(run.err_truth < tol)]
    assert t_cross >= (theta0 - tol) / w_max
    assert t_cross <= t_settle


@pytest.mark.parametrize("j", [J_DIAG, J_FULL], ids=["diagonal", "full"])
def test_tracking_orbit_rate_with_wheel_momentum(j: np.ndarray) -> None:
    g = AttitudeGains.gains_for(20.0, 0.9, w_max_radps=0.05)
    w_d = np.array([0.0, -N_ORBIT, 0.0])  # nadir-pointing-like: orbit rate about body −y
    r_d0 = Rotation.from_euler("xyz", [5.0, 50.0, -20.0], degrees=True)

    def desired(t: float) -> tuple[Rotation, np.ndarray, np.ndarray]:
        return r_d0 * Rotation.from_rotvec(w_d * t), w_d, np.zeros(3)

    h0 = np.array([0.01, 0.0, 0.0])  # ω × h ≠ 0: the gyroscopic coupling is active
    r0 = r_d0 * Rotation.from_rotvec([2.0 * DEG, -1.0 * DEG, 0.5 * DEG])
    run = _simulate(j, r0, np.zeros(3), h0, desired, g, 80.0)
    steady = run.t >= 50.0
    assert np.max(run.err_truth[steady]) < 0.01 * DEG
    assert np.all(np.abs(run.tau) <= TAU_MAX * (1.0 + 1e-12))
    assert np.all(np.abs(run.h) <= H_MAX)


def _lyapunov_rhs(
    j: np.ndarray, g: AttitudeGains, w_des: Callable[[float], np.ndarray],
    wdot_des: Callable[[float], np.ndarray],
) -> Callable[[float, np.ndarray], np.ndarray]:
    """Continuous closed loop; state [q, ω, h, q_des, ∫ kd |ω_e|² dt]."""
    j_inv = np.linalg.inv(j)

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        q, w, h, qd = y[0:4], y[4:7], y[7:10], y[10:14]
        r, r_d = Rotation.from_quat(q), Rotation.from_quat(qd)
        wd, wdd = w_des(t), wdot_des(t)
        tau, _ = tracking_torque(r, w, r_d, wd, wdd, j, h, g, math.inf)
        w_e = w - (r.inv() * r_d).apply(wd)
        return np.concatenate([
            _qdot(q, w),
            j_inv @ (tau - _cross(w, j @ w + h)),
            -tau,
            _qdot(qd, wd),
            [g.kd * float(w_e @ w_e)],
        ])

    return rhs


@pytest.mark.parametrize("case", ["regulation", "tracking"])
def test_lyapunov_function_decreases_as_designed(case: str) -> None:
    g = AttitudeGains.gains_for(20.0, 1.0)  # no rate limit, critically damped
    r_d0 = Rotation.from_euler("xyz", [30.0, -20.0, 10.0], degrees=True)
    h0 = np.array([0.004, -0.003, 0.005])
    if case == "regulation":
        def w_des(t: float) -> np.ndarray:
            return np.zeros(3)

        def wdot_des(t: float) -> np.ndarray:
            return np.zeros(3)

        r0, w0 = r_d0 * Rotation.from_rotvec(80.0 * DEG * np.array([0.36, 0.48, -0.8])), np.zeros(3)
    else:
        def w_des(t: float) -> np.ndarray:
            return np.array([0.01 * math.sin(0.2 * t), -N_ORBIT, 0.004])

        def wdot_des(t: float) -> np.ndarray:
            return np.array([0.002 * math.cos(0.2 * t), 0.0, 0.0])

        rng = np.random.default_rng(2)
        r0 = r_d0 * Rotation.from_rotvec(rng.normal(size=3) * 0.5)
        w0 = rng.normal(size=3) * 0.01
    y0 = np.concatenate([r0.as_quat(), w0, h0, r_d0.as_quat(), [0.0]])
    sol = solve_ivp(_lyapunov_rhs(J_FULL, g, w_des, wdot_des), (0.0, 40.0), y0,
                    method="DOP853", rtol=1e-10, atol=1e-12, t_eval=np.linspace(0.0, 40.0, 81))
    assert sol.success
    v = np.empty(sol.t.size)
    angle = np.empty(sol.t.size)
    for i, t in enumerate(sol.t):
        q = sol.y[0:4, i] / np.linalg.norm(sol.y[0:4, i])
        qd = sol.y[10:14, i] / np.linalg.norm(sol.y[10:14, i])
        dq = _qmul(np.concatenate([-qd[:3], [qd[3]]]), q)  # q_d* ⊗ q
        w_e = sol.y[4:7, i] - (Rotation.from_quat(q).inv() * Rotation.from_quat(qd)).apply(w_des(t))
        v[i] = 0.5 * float(w_e @ w_e) + 2.0 * g.kp * (1.0 - abs(dq[3]))
        angle[i] = 2.0 * math.atan2(float(np.linalg.norm(dq[:3])), abs(dq[3]))
    assert v[-1] < 1e-3 * v[0]
    assert np.all(np.diff(v) <= 1e-12)
    # V(0) − V(t) = ∫ kd |ω_e|² dt exactly (V̇ = −kd |ω_e|²)
    np.testing.assert_allclose(v[0] - v, sol.y[14], atol=1e-8 * v[0])
    if case == "regulation":  # eigen-axis, no overshoot at ζ = 1
        assert np.all(np.diff(angle) <= 1e-12)


def test_tracks_scp_slew_plan() -> None:
    r0 = Rotation.from_euler("xyz", [-15.0, 35.0, 60.0], degrees=True)
    r1 = r0 * Rotation.from_rotvec(90.0 * DEG * np.array([2.0, -1.0, 2.0]) / 3.0)
    plan = scp_slew(r0, r1, 60.0, 31, 0.035, w0=np.zeros(3), w1=np.zeros(3))
    assert plan.status == "solved"
    # at() gives ω̇ = 0 (piecewise-constant rates), so the PD lags the plan's
    # acceleration α by about 2α/kp: 5 s settling keeps that to ~0.2° (10 s: ~0.7°)
    g = AttitudeGains.gains_for(5.0, 0.9, w_max_radps=0.05)
    run = _simulate(J_FULL, r0, np.zeros(3), np.zeros(3), plan.at, g, 60.0)
    assert run.t[-1] == pytest.approx(plan.t_s[-1])
    assert (Rotation.from_quat(run.q[-1]).inv() * r1).magnitude() < 0.5 * DEG
    assert run.err_truth[-1] < 0.5 * DEG
    assert np.max(run.err_truth) < 0.5 * DEG
    assert np.all(np.abs(run.tau) <= TAU_MAX * (1.0 + 1e-12))
    assert np.all(np.abs(run.h) <= H_MAX)


def test_torque_saturation_keeps_direction() -> None:
    g = AttitudeGains.gains_for(5.0, 0.9)
    args = (Rotation.from_rotvec([1.0, -0.5, 0.2]), [0.02, 0.0, -0.01], Rotation.identity(),
            [0.0, 0.01, 0.0], [0.0, 0.0, 0.001], J_FULL, [0.0, 0.01, 0.0], g)
    free, err = tracking_torque(*args, math.inf)  # type: ignore[arg-type]
    sat, err2 = tracking_torque(*args, TAU_MAX)  # type: ignore[arg-type]
    assert err == err2 == pytest.approx(float(np.linalg.norm([1.0, -0.5, 0.2])))
    assert np.max(np.abs(free)) > 5.0 * TAU_MAX
    assert np.max(np.abs(sat)) == pytest.approx(TAU_MAX)
    assert _angle(free, sat) < 1e-12
    per_axis, _ = tracking_torque(*args, [1e-3, 5e-3, 5e-3])  # type: ignore[arg-type]
    assert np.all(np.abs(per_axis) <= [1e-3, 5e-3, 5e-3])
    assert _angle(free, per_axis) < 1e-12


def test_controller_bad_input() -> None:
    g = AttitudeGains.gains_for(10.0)
    ok = (Rotation.identity(), np.zeros(3), Rotation.identity(), np.zeros(3), np.zeros(3),
          J_DIAG, np.zeros(3), g, TAU_MAX)
    for i, bad in ((1, [np.nan, 0.0, 0.0]), (5, np.eye(2)),
                   (5, J_DIAG + np.triu(np.ones((3, 3)), 1)),
                   (6, [0.0, 0.0]), (8, 0.0), (8, -1.0), (8, np.nan)):
        args = list(ok)
        args[i] = bad
        with pytest.raises(ValueError):
            tracking_torque(*args)  # type: ignore[arg-type]
    for kwargs in ({"kp": -1.0, "kd": 1.0}, {"kp": 1.0, "kd": 0.0},
                   {"kp": 1.0, "kd": 1.0, "w_max_radps": math.nan}):
        with pytest.raises(ValueError):
            AttitudeGains(**kwargs)  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        AttitudeGains.gains_for(0.0)
    with pytest.raises(ValueError):
        AttitudeGains.gains_for(10.0, damping=-0.5)


def test_repoint_is_the_shortest_rotation_onto_the_line_of_sight() -> None:
    """repoint puts the boresight on the line of sight, turns by exactly the angle between them
    (the minimum for any rotation doing so) and never rotates about the boresight."""
    from fsw.lib.attitude import repoint

    rng = np.random.default_rng(7)
    bore = np.array([0.0, 0.0, 1.0])
    for _ in range(50):
        r0 = Rotation.random(random_state=rng)
        los = rng.standard_normal(3)
        r1 = repoint(r0, los, bore)
        c = los / np.linalg.norm(los)
        a = r0.apply(bore)
        assert np.allclose(r1.apply(bore), c, atol=1e-12)
        turn = (r0.inv() * r1).magnitude()
        assert turn == pytest.approx(np.arccos(np.clip(a @ c, -1, 1)), abs=1e-9)
        # no roll: the body-frame rotation axis is perpendicular to the boresight
        axis_body = (r0.inv() * r1).as_rotvec()
        assert abs(axis_body @ bore) < 1e-9
    r0 = Rotation.random(random_state=rng)
    assert repoint(r0, r0.apply(bore) * 3.0, bore).approx_equal(r0, atol=1e-12)
    flipped = repoint(r0, -r0.apply(bore), bore)
    assert np.allclose(flipped.apply(bore), -r0.apply(bore), atol=1e-12)
    assert (r0.inv() * flipped).magnitude() == pytest.approx(np.pi)


def test_plans_give_the_same_attitude_as_quaternion_and_rotation() -> None:
    """at_quat (the 10 Hz path) and at (scipy Rotation) describe the same plan."""
    rng = np.random.default_rng(3)
    r0, r1 = Rotation.random(random_state=rng), Rotation.random(random_state=rng)
    for plan in (slerp_plan(r0, r1, 0.0, 50.0), scp_slew(r0, r1, 120.0, 25, 0.05)):
        for t in (-1.0, 0.0, 7.3, 49.9, 50.0, 80.0, 130.0):
            r, w, wd = plan.at(t)
            q, wq, wdq = plan.at_quat(t)
            assert np.allclose(q, r.as_quat(), atol=1e-15)
            assert np.array_equal(w, wq) and np.array_equal(wd, wdq)
