"""Compiled kernels of the truth integrators (numba, cached on disk): one call per tick.

* :func:`attitude_rk4` — the rigid-body + reaction-wheel RK4 of :class:`sim.attitude.AttitudeTruth`
  (same equations, same stage order, quaternions renormalised after each substep), with the
  integral of the body rate the gyro senses;
* :func:`relative_rk4` — the chief + deputies RK4 of :class:`sim.dynamics.RelativeTruth`
  (Battin's differential gravity, optional J2, LVLH acceleration rotated into ECI at each stage);
* :func:`lvlh_attitudes`, :func:`thrust_accel_lvlh` and :func:`spend_and_hold` — the frame,
  thrust and Δv glue of :class:`sim.hardware.ObserverHardware` (the attitudes in LVLH, the
  thrust acceleration in LVLH, the Δv spent and the wheel torques held), and
  :func:`realise_wheel_torque`, :meth:`sim.actuators.WheelArray.realise`: the same
  floating-point operations in the same order as their numpy references, so the results are
  the same bits (numpy's clip, minimum and maximum written out as it computes them).

The numpy implementations in those classes stay the reference; ``tests/sim/test_kernels.py``
checks these against them on random states.  Inputs are float64 arrays, already validated by
the calling class.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from interfaces.contracts.timing import TIME_TOL_S


@njit(cache=True)
def _attitude_deriv(y: np.ndarray, J: np.ndarray, Jinv: np.ndarray, tau_total: np.ndarray,
                    tau_wheel: np.ndarray, out: np.ndarray) -> None:
    """d/dt of y = [q (4), w (3), h (3)] per row (AttitudeTruth._deriv)."""
    for i in range(y.shape[0]):
        qx, qy, qz, qs = y[i, 0], y[i, 1], y[i, 2], y[i, 3]
        wx, wy, wz = y[i, 4], y[i, 5], y[i, 6]
        mx = J[i, 0, 0] * wx + J[i, 0, 1] * wy + J[i, 0, 2] * wz + y[i, 7]
        my = J[i, 1, 0] * wx + J[i, 1, 1] * wy + J[i, 1, 2] * wz + y[i, 8]
        mz = J[i, 2, 0] * wx + J[i, 2, 1] * wy + J[i, 2, 2] * wz + y[i, 9]
        cx = wy * mz - wz * my
        cy = wz * mx - wx * mz
        cz = wx * my - wy * mx
        ax = tau_total[i, 0] - cx
        ay = tau_total[i, 1] - cy
        az = tau_total[i, 2] - cz
        for k in range(3):
            out[i, 4 + k] = Jinv[i, k, 0] * ax + Jinv[i, k, 1] * ay + Jinv[i, k, 2] * az
        out[i, 0] = 0.5 * (qs * wx + (qy * wz - qz * wy))
        out[i, 1] = 0.5 * (qs * wy + (qz * wx - qx * wz))
        out[i, 2] = 0.5 * (qs * wz + (qx * wy - qy * wx))
        out[i, 3] = -0.5 * (qx * wx + qy * wy + qz * wz)
        for k in range(3):
            out[i, 7 + k] = -tau_wheel[i, k]


@njit(cache=True)
def attitude_rk4(y0: np.ndarray, J: np.ndarray, Jinv: np.ndarray, tau_total: np.ndarray,
                 tau_wheel: np.ndarray, dt: float, substeps: int
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Advance y = [q, w, h] (N, 10) by ``dt`` (s) in ``substeps`` RK4 steps with the torques
    held (N·m), inertias J and their inverses (N, 3, 3); return (y, ∫w dt (N, 3), rad)."""
    n = y0.shape[0]
    hs = dt / substeps
    y = y0.copy()
    theta = np.zeros((n, 3))
    k1, k2, k3, k4 = np.empty_like(y), np.empty_like(y), np.empty_like(y), np.empty_like(y)
    tmp = np.empty_like(y)
    for _ in range(substeps):
        _attitude_deriv(y, J, Jinv, tau_total, tau_wheel, k1)
        tmp[:] = y + (0.5 * hs) * k1
        y2w = tmp[:, 4:7].copy()
        _attitude_deriv(tmp, J, Jinv, tau_total, tau_wheel, k2)
        tmp[:] = y + (0.5 * hs) * k2
        y3w = tmp[:, 4:7].copy()
        _attitude_deriv(tmp, J, Jinv, tau_total, tau_wheel, k3)
        tmp[:] = y + hs * k3
        _attitude_deriv(tmp, J, Jinv, tau_total, tau_wheel, k4)
        theta += (hs / 6.0) * (y[:, 4:7] + 2.0 * (y2w + y3w) + tmp[:, 4:7])
        y = y + (hs / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
        for i in range(n):
            norm = math.sqrt(y[i, 0] ** 2 + y[i, 1] ** 2 + y[i, 2] ** 2 + y[i, 3] ** 2)
            for k in range(4):
                y[i, k] /= norm
    return y, theta


@njit(cache=True)
def _lvlh_basis(c: np.ndarray) -> np.ndarray:
    """Rows x, y, z of the chief's LVLH frame in ECI (dynamics._basis_and_rate)."""
    rx, ry, rz, vx, vy, vz = c[0], c[1], c[2], c[3], c[4], c[5]
    hx = ry * vz - rz * vy
    hy = rz * vx - rx * vz
    hz = rx * vy - ry * vx
    rn = math.sqrt(rx * rx + ry * ry + rz * rz)
    hn = math.sqrt(hx * hx + hy * hy + hz * hz)
    xr, yr, zr = rx / rn, ry / rn, rz / rn
    xh, yh, zh = hx / hn, hy / hn, hz / hn
    b = np.empty((3, 3))
    b[0, 0], b[0, 1], b[0, 2] = xr, yr, zr
    b[1, 0], b[1, 1], b[1, 2] = yh * zr - zh * yr, zh * xr - xh * zr, xh * yr - yh * xr
    b[2, 0], b[2, 1], b[2, 2] = xh, yh, zh
    return b


@njit(cache=True)
def _relative_deriv(y: np.ndarray, a_lvlh: np.ndarray, has_accel: bool, mu: float,
                    j2: bool, j2_k: float, out: np.ndarray) -> None:
    """d/dt of the stacked state: row 0 chief absolute, rows 1.. relative (RelativeTruth)."""
    rcx, rcy, rcz = y[0, 0], y[0, 1], y[0, 2]
    rc2 = rcx * rcx + rcy * rcy + rcz * rcz
    k = mu / (rc2 * math.sqrt(rc2))
    acx, acy, acz = -k * rcx, -k * rcy, -k * rcz
    jcx = jcy = jcz = 0.0
    if j2:
        kc = j2_k / (rc2 * rc2 * math.sqrt(rc2))
        gc = kc * (1.0 - 5.0 * rcz * rcz / rc2)
        jcx, jcy, jcz = gc * rcx, gc * rcy, (gc + 2.0 * kc) * rcz
        acx += jcx
        acy += jcy
        acz += jcz
    basis = _lvlh_basis(y[0]) if has_accel else np.eye(3)
    for c in range(3):
        out[0, c] = y[0, 3 + c]
    out[0, 3], out[0, 4], out[0, 5] = acx, acy, acz
    for i in range(1, y.shape[0]):
        dx, dy, dz = y[i, 0], y[i, 1], y[i, 2]
        p = (dx * dx + dy * dy + dz * dz) + 2.0 * (dx * rcx + dy * rcy + dz * rcz)
        rd2 = p + rc2
        q = -p / rd2
        opq = rc2 / rd2
        f = q * (3.0 + q * (3.0 + q)) / (1.0 + opq * math.sqrt(opq))
        rdx, rdy, rdz = dx + rcx, dy + rcy, dz + rcz
        ax = -k * (rdx * f + dx)
        ay = -k * (rdy * f + dy)
        az = -k * (rdz * f + dz)
        if j2:
            kd = j2_k / (rd2 * rd2 * math.sqrt(rd2))
            gd = kd * (1.0 - 5.0 * rdz * rdz / rd2)
            ax += rdx * gd - jcx
            ay += rdy * gd - jcy
            az += rdz * gd + 2.0 * kd * rdz - jcz
        if has_accel:
            a0, a1, a2 = a_lvlh[i - 1, 0], a_lvlh[i - 1, 1], a_lvlh[i - 1, 2]
            ax += a0 * basis[0, 0] + a1 * basis[1, 0] + a2 * basis[2, 0]
            ay += a0 * basis[0, 1] + a1 * basis[1, 1] + a2 * basis[2, 1]
            az += a0 * basis[0, 2] + a1 * basis[1, 2] + a2 * basis[2, 2]
        for c in range(3):
            out[i, c] = y[i, 3 + c]
        out[i, 3], out[i, 4], out[i, 5] = ax, ay, az


@njit(cache=True)
def relative_rk4(y0: np.ndarray, a_lvlh: np.ndarray, has_accel: bool, mu: float, j2: bool,
                 j2_k: float, dt: float, substeps: int) -> np.ndarray:
    """Advance the stacked chief/deputy state (N+1, 6) by ``dt`` (s) in ``substeps`` RK4 steps;
    ``a_lvlh`` (N, 3), m/s², held over the call when ``has_accel``."""
    h = dt / substeps
    y = y0.copy()
    k1, k2, k3, k4 = np.empty_like(y), np.empty_like(y), np.empty_like(y), np.empty_like(y)
    for _ in range(substeps):
        _relative_deriv(y, a_lvlh, has_accel, mu, j2, j2_k, k1)
        _relative_deriv(y + (0.5 * h) * k1, a_lvlh, has_accel, mu, j2, j2_k, k2)
        _relative_deriv(y + (0.5 * h) * k2, a_lvlh, has_accel, mu, j2, j2_k, k3)
        _relative_deriv(y + h * k3, a_lvlh, has_accel, mu, j2, j2_k, k4)
        s = 2.0 * (k2 + k3)  # the reference's order of additions
        s += k1
        s += k4
        y = y + (h / 6.0) * s
    return y


@njit(cache=True)
def lvlh_attitudes(q_lvlh_eci: np.ndarray, q_eci_body: np.ndarray) -> np.ndarray:
    """R_lvlh_body = R_lvlh_eci R_eci_body per spacecraft (N, 4), scalar last: the Hamilton
    product of :func:`gnc.quat.mul` with the frame quaternion (4,) on every row."""
    n = q_eci_body.shape[0]
    out = np.empty((n, 4))
    px, py, pz, pw = q_lvlh_eci[0], q_lvlh_eci[1], q_lvlh_eci[2], q_lvlh_eci[3]
    for i in range(n):
        qx, qy, qz, qw = q_eci_body[i, 0], q_eci_body[i, 1], q_eci_body[i, 2], q_eci_body[i, 3]
        out[i, 0] = pw * qx + qw * px + py * qz - pz * qy
        out[i, 1] = pw * qy + qw * py + pz * qx - px * qz
        out[i, 2] = pw * qz + qw * pz + px * qy - py * qx
        out[i, 3] = pw * qw - px * qx - py * qy - pz * qz
    return out


@njit(cache=True)
def thrust_accel_lvlh(q_lvlh_body: np.ndarray, force_body: np.ndarray, force_until: np.ndarray,
                      force_bias_body: np.ndarray, t_s: float, mass_kg: float) -> np.ndarray:
    """Thrust acceleration in LVLH (N, 3), m/s²: the commanded force while its command runs
    (``t_s`` before ``force_until`` less 1 ns) plus the continuous bias, body axes (N), rotated
    by R(q_lvlh_body) (:func:`gnc.quat.rotate`) and divided by the mass (kg)."""
    n = force_body.shape[0]
    out = np.empty((n, 3))
    for i in range(n):
        active = t_s < force_until[i] - TIME_TOL_S
        vx = (force_body[i, 0] if active else 0.0) + force_bias_body[i, 0]
        vy = (force_body[i, 1] if active else 0.0) + force_bias_body[i, 1]
        vz = (force_body[i, 2] if active else 0.0) + force_bias_body[i, 2]
        qx, qy, qz, qw = q_lvlh_body[i, 0], q_lvlh_body[i, 1], q_lvlh_body[i, 2], q_lvlh_body[i, 3]
        tx = 2.0 * (qy * vz - qz * vy)
        ty = 2.0 * (qz * vx - qx * vz)
        tz = 2.0 * (qx * vy - qy * vx)
        out[i, 0] = (vx + qw * tx + qy * tz - qz * ty) / mass_kg
        out[i, 1] = (vy + qw * ty + qz * tx - qx * tz) / mass_kg
        out[i, 2] = (vz + qw * tz + qx * ty - qy * tx) / mass_kg
    return out


@njit(cache=True)
def spend_and_hold(dv_mps: np.ndarray, force_body: np.ndarray, force_until: np.ndarray,
                   force_bias_body: np.ndarray, tau_cmd: np.ndarray, tau_until: np.ndarray,
                   t_s: float, dt_s: float, mass_kg: float) -> np.ndarray:
    """Add this tick's Δv (m/s; commanded force while it runs and the leak, each spent in
    full) to ``dv_mps`` in place, and return the wheel torques held (N·m, zero once a command
    is older than its hold)."""
    n = force_body.shape[0]
    held = np.empty((n, 3))
    for i in range(n):
        active = t_s < force_until[i] - TIME_TOL_S
        spent = 0.0
        for k in range(3):
            f = abs(force_body[i, k] if active else 0.0) + abs(force_bias_body[i, k])
            spent = f if k == 0 else spent + f
        dv_mps[i] += spent * dt_s / mass_kg
        holding = t_s < tau_until[i] - TIME_TOL_S
        for k in range(3):
            held[i, k] = tau_cmd[i, k] if holding else 0.0
    return held


@njit(cache=True)
def realise_wheel_torque(tau_cmd: np.ndarray, h: np.ndarray, scale: np.ndarray,
                         bias: np.ndarray, tau_max: np.ndarray, h_max: np.ndarray, dt: float
                         ) -> np.ndarray:
    """The torque the wheels realise on the body over a tick (N, 3), N·m: the command scaled
    and biased, clipped to the torque limit, then recomputed on the axes whose momentum
    (N·m·s) would cross its limit (:meth:`sim.actuators.WheelArray.realise`)."""
    n = tau_cmd.shape[0]
    out = np.empty((n, 3))
    for i in range(n):
        for k in range(3):
            tau = scale[i, k] * tau_cmd[i, k] + bias[i, k]
            lo, hi = -tau_max[k], tau_max[k]
            tau = tau if tau > lo else lo  # np.clip: max first, then min
            tau = tau if tau < hi else hi
            h0 = h[i, k]
            h_end = h0 - tau * dt
            lo = -h_max[k] if -h_max[k] <= h0 else h0  # np.minimum(-h_max, h0)
            hi = h_max[k] if h_max[k] >= h0 else h0  # np.maximum(h_max, h0)
            h_lim = h_end if h_end > lo else lo
            h_lim = h_lim if h_lim < hi else hi
            out[i, k] = (h0 - h_lim) / dt if h_lim != h_end else tau
    return out
