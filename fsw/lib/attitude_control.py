"""Attitude tracking control: quaternion-feedback law with gyroscopic compensation.

Plant (rigid body with reaction wheels, body axes)::

    J ω̇ = −ω × (J ω + h) + τ,      ḣ = −τ,      Ṙ = R [ω]×

with ``J`` the inertia (kg·m²), ``ω`` the body rate w.r.t. inertial (rad/s), ``h``
the wheel momentum (N·m·s) and ``τ`` the commanded torque on the body (N·m),
realised by the wheels.  Attitudes are ``R_ref_body`` (body → an inertial reference
frame), given as scipy Rotations or as scalar-last quaternion arrays (4,); the algebra is
done on the quaternions with :mod:`gnc.quat` (scipy's Rotation costs tens of µs per
operation).

Control law (quaternion error feedback with feed-forward and gyroscopic
compensation; Wie, Weiss & Arapostathis, "Quaternion feedback regulator for
spacecraft eigenaxis rotations", JGCD 12(3), 1989; Wie, *Space Vehicle Dynamics and
Control*, 2nd ed., Sec. 7.3)::

    δR  = R_des⁻¹ R_body          (body w.r.t. desired; δq with δq_w ≥ 0: short way)
    C   = δRᵀ                     (maps desired-frame components to body components)
    ω_e = ω − C ω_d                (rate error, body axes)
    ω_c = −(kp/kd) δq_v, scaled down to |ω_c| ≤ w_max when a rate limit is set
    a   = −kd (ω_e − ω_c)          (= −kp δq_v − kd ω_e when not rate limited)
    τ   = J (a + C ω̇_d − ω × C ω_d) + ω × (J ω + h)

Closed loop without limits: ``d/dt(C ω_d) = C ω̇_d − ω × C ω_d``, so
``ω̇_e = −kp δq_v − kd ω_e`` exactly, and with ``δq̇_w = −½ δq_vᵀ ω_e``
the function ``V = ½|ω_e|² + 2 kp (1 − δq_w)`` has ``V̇ = −kd |ω_e|² ≤ 0``
(Wie et al. 1989).

Rate-limited mode (large errors): the bracket ``ω_e − ω_c`` is a rate loop around
the "error-rate command" ``ω_c``; saturating ``|ω_c| ≤ w_max`` (direction kept, so
the rotation stays about the eigen-axis) makes the body turn toward the desired
attitude at no more than ``w_max`` relative to the desired motion.  With exact
model and no torque saturation ``ω̇_e = −kd (ω_e − ω_c)`` is a first-order
low-pass of ``ω_c``, hence ``|ω_e(t)| ≤ max(|ω_e(0)|, w_max)``.  Inside the linear
region ``(kp/kd)|δq_v| ≤ w_max`` the law is the plain PD above.  This is the
rate-limited eigen-axis logic of Wie & Lu, "Feedback control logic for spacecraft
eigenaxis rotations under slew rate and control constraints", JGCD 18(6), 1995.

Torque limit: the per-axis limit is met by scaling the whole vector,
``τ ← τ · min(1, min_j τ_max,j / |τ_j|)``, which keeps its direction.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from gnc import quat
from gnc.attitude_gains import AttitudeGains, gains_for
from gnc.checks import finite_array

__all__ = ["AttitudeGains", "gains_for", "tracking_torque"]

FloatArray = npt.NDArray[np.float64]


def _attitude_quat(name: str, r: Rotation | npt.ArrayLike) -> FloatArray:
    """Unit quaternion (4,) of a single scipy Rotation or of a finite non-zero (4,) array."""
    if isinstance(r, Rotation):
        if not r.single:
            raise ValueError(f"{name} must be a single scipy Rotation")
        q = r.as_quat()
        if not np.isfinite(q).all():
            raise ValueError(f"{name} contains NaN or infinite values")
    else:
        q = finite_array(name, r, (4,))
    norm = math.hypot(*q.tolist())
    if not norm > 0.0:
        raise ValueError(f"{name} must be a non-zero quaternion")
    return q / norm


def tracking_torque(
    r_est: Rotation | npt.ArrayLike,
    w_est: npt.ArrayLike,
    r_des: Rotation | npt.ArrayLike,
    w_des: npt.ArrayLike,
    wdot_des: npt.ArrayLike,
    J: npt.ArrayLike,
    h_wheels: npt.ArrayLike,
    gains: AttitudeGains,
    tau_max_nm: float | npt.ArrayLike,
) -> tuple[FloatArray, float]:
    """Body torque command of the quaternion-feedback tracking law (module docstring).

    Args:
        r_est: estimated attitude ``R_ref_body``: a single scipy Rotation or a
            scalar-last quaternion (4,) (either sign, normalised here).
        w_est: estimated body rate, rad/s, body axes (3,).
        r_des: desired attitude ``R_ref_des``, a Rotation or a quaternion (4,) as r_est.
        w_des: desired rate, rad/s, in desired-frame axes (3,) (what plans return).
        wdot_des: desired angular acceleration, rad/s², desired-frame axes (3,).
        J: inertia, kg·m², (3, 3) symmetric.
        h_wheels: wheel momentum, N·m·s, body axes (3,).
        gains: controller gains.
        tau_max_nm: per-axis torque limit, N·m: a scalar or (3,), > 0 (``inf`` for
            none).

    Returns:
        ``(tau_body, error_angle_rad)``: the torque on the body, N·m (3,), with
        ``|τ_j| ≤ τ_max,j``; and the attitude error angle ``2 atan2(|δq_v|, |δq_w|)``
        in [0, π], rad (telemetry).

    Raises:
        ValueError: non-finite or ill-shaped inputs (a Rotation holding several
            rotations, a zero quaternion), a non-symmetric J or a non-positive torque
            limit.
    """
    q_est = _attitude_quat("r_est", r_est)
    q_des = _attitude_quat("r_des", r_des)
    w = finite_array("w_est", w_est, (3,))
    wd = finite_array("w_des", w_des, (3,))
    wdd = finite_array("wdot_des", wdot_des, (3,))
    h = finite_array("h_wheels", h_wheels, (3,))
    jm = finite_array("J", J, (3, 3))
    if float(np.abs(jm - jm.T).max()) > 1e-9 * float(np.abs(jm).max()):
        raise ValueError("J must be symmetric")
    tmax = np.asarray(tau_max_nm, dtype=float)
    if tmax.shape not in ((), (3,)) or not bool((tmax > 0.0).all()):
        raise ValueError(f"tau_max_nm must be positive, scalar or (3,), got {tau_max_nm!r}")

    # δq of δR = R_des⁻¹ R_body (body → desired), short way
    dq = quat.canonical(quat.mul(quat.conj(q_des), q_est))
    dq_v = dq[:3]
    err_angle = 2.0 * math.atan2(math.hypot(*dq_v.tolist()), float(dq[3]))

    # C = δRᵀ: desired-frame components → body components
    wd_b = quat.rotate_inv(dq, wd)
    w_err = w - wd_b
    w_cmd = -(gains.kp / gains.kd) * dq_v
    if gains.w_max_radps is not None:
        norm_cmd = math.hypot(*w_cmd.tolist())
        if norm_cmd > gains.w_max_radps:
            w_cmd *= gains.w_max_radps / norm_cmd
    accel = -gains.kd * (w_err - w_cmd) + quat.rotate_inv(dq, wdd) - quat.cross(w, wd_b)
    tau = jm @ accel + quat.cross(w, jm @ w + h)

    ratio = float((np.abs(tau) / tmax).max())
    if ratio > 1.0:
        tau = tau / ratio
    return tau, err_angle
