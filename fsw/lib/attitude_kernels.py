"""Compiled kernels of the 10 Hz attitude chain: MEKF step, pointing reference, tracking law.

The same mathematics as the reference implementations, fused into a few compiled calls per
cycle (numba, cached on disk), because on 3-vectors numpy's per-call overhead, not arithmetic,
set the cost (≈0.5 ms per spacecraft step with numpy, tens of µs compiled):

* :func:`mekf_propagate` / :func:`mekf_update` — :func:`fsw.lib.mekf.mekf_propagate` /
  :func:`fsw.lib.mekf.mekf_update` for one filter (Crassidis & Junkins §7.2; the Joseph form and
  the Mueller et al. 2017 reset);
* :func:`pointing_reference` — the desired attitude by :func:`fsw.lib.attitude.repoint` onto the
  line of sight, and its rate and acceleration by central differences of the repointed attitudes
  ``h`` before and after (the attitude app's feed-forward);
* :func:`tracking_torque` — :func:`fsw.lib.attitude_control.tracking_torque`;
* :func:`track_cycle` — the attitude app's whole tracking cycle in one call: the lines of sight,
  the pointing reference, its distance from the estimate and, below the slew threshold, the
  tracking torque (the kernels above composed, so the same bits as calling them one by one).

Inputs are float64 arrays already validated (finite, unit quaternions where stated): the
attitude app feeds them from validated messages and its own state.  The numpy versions stay
the tested reference; ``tests/fsw/lib/test_attitude_kernels.py`` checks these against them on
random inputs.  Quaternions are scalar last [x, y, z, w], as in :mod:`gnc.quat`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from gnc import quat

_PHI_SERIES_RAD = 1e-2


@njit(cache=True)
def _qmul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    px, py, pz, pw = p[0], p[1], p[2], p[3]
    qx, qy, qz, qw = q[0], q[1], q[2], q[3]
    out = np.empty(4)
    out[0] = pw * qx + px * qw + py * qz - pz * qy
    out[1] = pw * qy - px * qz + py * qw + pz * qx
    out[2] = pw * qz + px * qy - py * qx + pz * qw
    out[3] = pw * qw - px * qx - py * qy - pz * qz
    return out


@njit(cache=True)
def _qconj(q: np.ndarray) -> np.ndarray:
    return np.array([-q[0], -q[1], -q[2], q[3]])


@njit(cache=True)
def _qrot(q: np.ndarray, v: np.ndarray, sign: float) -> np.ndarray:
    """R(q) v (sign 1) or R(q)ᵀ v (sign -1), as gnc.quat._rotated."""
    qx, qy, qz, qw = sign * q[0], sign * q[1], sign * q[2], q[3]
    vx, vy, vz = v[0], v[1], v[2]
    tx = 2.0 * (qy * vz - qz * vy)
    ty = 2.0 * (qz * vx - qx * vz)
    tz = 2.0 * (qx * vy - qy * vx)
    out = np.empty(3)
    out[0] = vx + qw * tx + qy * tz - qz * ty
    out[1] = vy + qw * ty + qz * tx - qx * tz
    out[2] = vz + qw * tz + qx * ty - qy * tx
    return out


@njit(cache=True)
def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@njit(cache=True)
def _norm3(v: np.ndarray) -> float:
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


_exp_xyz = njit(cache=True)(quat.exp_xyz)


@njit(cache=True)
def _qexp(v: np.ndarray) -> np.ndarray:
    qx, qy, qz, qw = _exp_xyz(v[0], v[1], v[2])
    return np.array([qx, qy, qz, qw])


@njit(cache=True)
def _qlog(q: np.ndarray) -> np.ndarray:
    x, y, z, w = q[0], q[1], q[2], q[3]
    lead = x if x != 0.0 else (y if y != 0.0 else z)
    if w < 0.0 or (w == 0.0 and lead < 0.0):
        x, y, z, w = -x, -y, -z, -w
    s = math.sqrt(x * x + y * y + z * z)
    k = 2.0 * math.atan2(s, w) / s if s > 0.0 else 2.0 / w
    return np.array([k * x, k * y, k * z])


@njit(cache=True)
def _canonical(q: np.ndarray) -> np.ndarray:
    return -q if q[3] < 0.0 else q.copy()


@njit(cache=True)
def _unit(v: np.ndarray) -> np.ndarray:
    return v / _norm3(v)


@njit(cache=True)
def _normalize4(q: np.ndarray) -> np.ndarray:
    return q / math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])


@njit(cache=True)
def _skew(v: np.ndarray) -> np.ndarray:
    m = np.zeros((3, 3))
    m[0, 1], m[0, 2] = -v[2], v[1]
    m[1, 0], m[1, 2] = v[2], -v[0]
    m[2, 0], m[2, 1] = -v[1], v[0]
    return m


# --- MEKF ---------------------------------------------------------------------------------


@njit(cache=True)
def mekf_propagate(q: np.ndarray, b: np.ndarray, P: np.ndarray, w_meas: np.ndarray, dt: float,
                   sigma_v: float, sigma_u: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MEKF time update over ``dt`` (s) with the mean gyro rate ``w_meas`` (rad/s): (q, b, P).
    As :func:`fsw.lib.mekf.mekf_propagate` for one filter."""
    qn = _normalize4(q)
    w = w_meas - b
    x = _norm3(w) * dt
    x2 = x * x
    if x < _PHI_SERIES_RAD:
        s0 = 1.0 - x2 / 6.0 + x2 * x2 / 120.0
        c1 = 0.5 - x2 / 24.0 + x2 * x2 / 720.0
        c2 = 1.0 / 6.0 - x2 / 120.0 + x2 * x2 / 5040.0
    else:
        sx, cx = math.sin(x), math.cos(x)
        s0, c1, c2 = sx / x, (1.0 - cx) / x2, (x - sx) / (x2 * x)
    W = _skew(w)
    W2 = W @ W
    eye = np.eye(3)
    phi = np.zeros((6, 6))
    phi[:3, :3] = eye - dt * s0 * W + dt**2 * c1 * W2
    phi[:3, 3:] = -dt * eye + dt**2 * c1 * W - dt**3 * c2 * W2
    phi[3:, 3:] = eye
    Q = np.zeros((6, 6))
    su2 = sigma_u * sigma_u
    for i in range(3):
        Q[i, i] = sigma_v * sigma_v * dt + su2 * dt**3 / 3.0
        Q[i, i + 3] = Q[i + 3, i] = -0.5 * su2 * dt**2
        Q[i + 3, i + 3] = su2 * dt
    P_new = phi @ P @ phi.T + Q
    q_new = _canonical(_qmul(qn, _qexp(w * dt)))
    return q_new, b.copy(), 0.5 * (P_new + P_new.T)


@njit(cache=True)
def mekf_update(q: np.ndarray, b: np.ndarray, P: np.ndarray, q_meas: np.ndarray, R: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """MEKF star-tracker update (Joseph form, reset): (q, b, P, NIS).  As
    :func:`fsw.lib.mekf.mekf_update` for one filter."""
    qa = _normalize4(q)
    nu = _qlog(_qmul(_qconj(qa), _normalize4(q_meas)))
    S = P[:3, :3] + R
    S_inv = np.linalg.inv(S)
    K = np.ascontiguousarray(P[:, :3]) @ S_inv
    dx = K @ nu
    I_KH = np.eye(6)
    I_KH[:, :3] -= K
    P_new = I_KH @ P @ I_KH.T + K @ R @ K.T
    G = np.eye(6)
    G[:3, :3] -= 0.5 * _skew(dx[:3])
    P_new = G @ P_new @ G.T
    q_new = _canonical(_qmul(qa, _qexp(dx[:3])))
    nis = nu @ (S_inv @ nu)
    return q_new, b + dx[3:], 0.5 * (P_new + P_new.T), nis


# --- pointing -----------------------------------------------------------------------------


@njit(cache=True)
def repoint(q_prev: np.ndarray, los: np.ndarray, boresight: np.ndarray) -> np.ndarray:
    """The attitude nearest to ``q_prev`` with the boresight on ``los``
    (:func:`fsw.lib.attitude.repoint` on quaternions)."""
    qp = _normalize4(q_prev)
    c = _unit(los)
    bb = _unit(boresight)
    a = _qrot(qp, bb, 1.0)
    axis = _cross(a, c)
    s = _norm3(axis)
    cos = a[0] * c[0] + a[1] * c[1] + a[2] * c[2]
    if s < 1e-12:
        if cos > 0.0:
            return q_prev.copy()
        k = int(np.argmin(np.abs(bb)))
        e = np.zeros(3)
        e[k] = 1.0
        axis = _qrot(qp, _cross(bb, e), 1.0)
        turn = axis * (math.pi / _norm3(axis))
    else:
        turn = axis * (math.atan2(s, cos) / s)
    return _qmul(_qexp(turn), qp)


@njit(cache=True)
def pointing_reference(q_seed: np.ndarray, los_prev: np.ndarray, los_now: np.ndarray,
                       los_next: np.ndarray, boresight: np.ndarray, h: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Desired attitude on ``los_now`` repointed from ``q_seed``, and its body rate (rad/s) and
    acceleration (rad/s²) by central differences of the attitudes repointed onto the lines of
    sight ``h`` seconds before and after."""
    q_des = repoint(q_seed, los_now, boresight)
    q_prev = repoint(q_des, los_prev, boresight)
    q_next = repoint(q_des, los_next, boresight)
    back = _qlog(_qmul(_qconj(q_prev), q_des))
    ahead = _qlog(_qmul(_qconj(q_des), q_next))
    return q_des, (back + ahead) / (2.0 * h), (ahead - back) / (h * h)


@njit(cache=True)
def angle_between(q_a: np.ndarray, q_b: np.ndarray) -> float:
    """Rotation angle from q_a to q_b, |Log(q_a⁻¹ q_b)|, rad."""
    return _norm3(_qlog(_qmul(_qconj(q_a), q_b)))


@njit(cache=True)
def lvlh_to_eci_quat(t_s: float, n: float, inclination_rad: float, raan_rad: float,
                     arg_lat0_rad: float) -> np.ndarray:
    """:func:`gnc.frames.lvlh_to_eci_quat`, compiled."""
    u = arg_lat0_rad + n * t_s
    half_i = 0.5 * inclination_rad
    diff, total = 0.5 * (raan_rad - u), 0.5 * (raan_rad + u)
    si, ci = math.sin(half_i), math.cos(half_i)
    q = np.array([si * math.cos(diff), si * math.sin(diff), ci * math.sin(total),
                  ci * math.cos(total)])
    largest = q[0]
    for k in range(1, 4):
        if abs(q[k]) > abs(largest):
            largest = q[k]
    return q if largest >= 0.0 else -q


@njit(cache=True)
def los_eci(t: float, n: float, inclination_rad: float, raan_rad: float, arg_lat0_rad: float,
            x_est: np.ndarray, t_est: float, target: np.ndarray, target_rate: np.ndarray,
            target_accel: np.ndarray, target_t: float) -> np.ndarray:
    """Line of sight (ECI, m) from the own position (nav estimate extrapolated with its
    velocity) to the pointing target (extrapolated to second order) at time ``t``; the
    target's orbit is circular (mean motion ``n``, inclination, node, argument of latitude at
    t = 0: :func:`lvlh_to_eci_quat`)."""
    dt_tgt = t - target_t
    aim = target + (target_rate + 0.5 * dt_tgt * target_accel) * dt_tgt
    r = x_est[:3] + x_est[3:] * (t - t_est)
    return _qrot(lvlh_to_eci_quat(t, n, inclination_rad, raan_rad, arg_lat0_rad), aim - r, 1.0)


# --- control ------------------------------------------------------------------------------


@njit(cache=True)
def tracking_torque(q_est: np.ndarray, w_est: np.ndarray, q_des: np.ndarray, w_des: np.ndarray,
                    wdot_des: np.ndarray, J: np.ndarray, h_wheels: np.ndarray, kp: float,
                    kd: float, w_max: float, tau_max: float) -> tuple[np.ndarray, float]:
    """Quaternion-feedback tracking law (:func:`fsw.lib.attitude_control.tracking_torque`):
    body torque (N·m), scaled to the per-axis limit, and the error angle (rad).  ``w_max``
    < 0 means no rate limit."""
    qe, qd = _normalize4(q_est), _normalize4(q_des)
    dq = _canonical(_qmul(_qconj(qd), qe))
    dq_v = dq[:3]
    err_angle = 2.0 * math.atan2(_norm3(dq_v), dq[3])
    wd_b = _qrot(dq, w_des, -1.0)
    w_err = w_est - wd_b
    w_cmd = -(kp / kd) * dq_v
    if w_max >= 0.0:
        norm_cmd = _norm3(w_cmd)
        if norm_cmd > w_max:
            w_cmd = w_cmd * (w_max / norm_cmd)
    accel = -kd * (w_err - w_cmd) + _qrot(dq, wdot_des, -1.0) - _cross(w_est, wd_b)
    tau = J @ accel + _cross(w_est, J @ w_est + h_wheels)
    ratio = np.abs(tau).max() / tau_max
    if ratio > 1.0:
        tau = tau / ratio
    return tau, err_angle


TRACKED = 0
""":func:`track_cycle` status: the pointing attitude is tracked (the torque is computed)."""
SLEW = 1
""":func:`track_cycle` status: the estimate is beyond the slew threshold (no torque: plan a
slew)."""
NO_LINE_OF_SIGHT = 2
""":func:`track_cycle` status: a line of sight is zero or not finite (its time is returned)."""


@njit(cache=True)
def track_cycle(t: float, h: float, n: float, inclination_rad: float, raan_rad: float,
                arg_lat0_rad: float, x_est: np.ndarray, t_est: float, target: np.ndarray,
                target_rate: np.ndarray,
                target_accel: np.ndarray, target_t: float, q_seed: np.ndarray,
                q_est: np.ndarray, w_est: np.ndarray, boresight: np.ndarray, J: np.ndarray,
                h_wheels: np.ndarray, kp: float, kd: float, w_max: float, tau_max: float,
                slew_threshold_rad: float
                ) -> tuple[int, float, np.ndarray, float, np.ndarray]:
    """One tracking cycle at time ``t`` (s): the lines of sight (:func:`los_eci`) ``h`` seconds
    before, at and after ``t``; the pointing reference repointed from ``q_seed``
    (:func:`pointing_reference`); its angle from the estimate ``q_est`` (rad); and, when that
    angle is within ``slew_threshold_rad``, the tracking torque (:func:`tracking_torque`, N·m).

    Returns (status, time s of a bad line of sight, desired attitude, angle rad, torque N·m):
    status :data:`TRACKED`, :data:`SLEW` (torque zero) or :data:`NO_LINE_OF_SIGHT`."""
    zero4, zero3 = np.zeros(4), np.zeros(3)
    lines = np.empty((3, 3))
    for j in range(3):
        tj = t + (j - 1) * h
        los = los_eci(tj, n, inclination_rad, raan_rad, arg_lat0_rad, x_est, t_est, target,
                      target_rate, target_accel, target_t)
        n2 = los[0] * los[0] + los[1] * los[1] + los[2] * los[2]
        if not (n2 > 0.0 and math.isfinite(n2)):
            return NO_LINE_OF_SIGHT, tj, zero4, 0.0, zero3
        lines[j] = los
    q_des, w_des, wdot_des = pointing_reference(q_seed, lines[0], lines[1], lines[2],
                                                boresight, h)
    angle = angle_between(q_des, q_est)
    if angle > slew_threshold_rad:
        return SLEW, t, q_des, angle, zero3
    tau, _ = tracking_torque(q_est, w_est, q_des, w_des, wdot_des, J, h_wheels, kp, kd, w_max,
                             tau_max)
    return TRACKED, t, q_des, angle, tau
