"""Multiplicative extended Kalman filter (MEKF) for attitude and gyro bias (pure functions).

References: Lefferts, Markley & Shuster, "Kalman filtering for spacecraft attitude estimation",
JGCD 5(5), 1982; Crassidis & Junkins, *Optimal Estimation of Dynamic Systems*, 2nd ed., §7.2
(the filter equations, Φ and Q below); Markley & Crassidis, *Fundamentals of Spacecraft Attitude
Determination and Control*, 2014, §6.2; Mueller, Hehn & D'Andrea, "Covariance correction step for
Kalman filtering with an attitude", JGCD 40(9), 2017 (the reset Jacobian).

State and conventions:

* attitude estimate ``R̂ = R_eci_body`` as a scalar-last unit quaternion ``q`` [x, y, z, w]
  (returned with ``w >= 0``), gyro bias estimate ``b`` (body axes, rad/s);
* error state ``x = [δθ, Δb]`` (6,), with ``R_true = R̂ Exp(δθ)`` (δθ a small rotation vector
  in body axes, rad) and ``Δb = b_true - b̂`` (rad/s); ``P`` its 6×6 covariance;
* gyro model (Farrenkopf): ``w_meas = w + b + η_v``, ``ḃ = η_u`` with spectral densities
  ``sigma_v²`` (rad²/s) and ``sigma_u²`` (rad²/s³); the measured rate is the average over the
  interval, so the bias-corrected rate ``ŵ = w_meas - b̂`` is held constant over ``dt``;
* star tracker: ``R_meas = R_true Exp(v)``, ``v ~ N(0, R)`` in body axes; the measurement is the
  small-angle residual ``ν = Log(R̂ᵀ R_meas) ≈ δθ + v`` with ``H = [I 0]``.

Error dynamics ``δθ̇ = -[ŵ×] δθ - Δb - η_v``, ``Δḃ = η_u`` give the discrete transition over
``dt`` with ``x = |ŵ| dt`` (Crassidis & Junkins §7.2.1)::

    Φ11 = exp(-[ŵ×] dt) = I - [ŵ×] sin x / |ŵ| + [ŵ×]² (1 - cos x) / |ŵ|²
    Φ12 = -I dt + [ŵ×] (1 - cos x) / |ŵ|² - [ŵ×]² (x - sin x) / |ŵ|³
    Φ21 = 0,  Φ22 = I
    Q   = [[(σv² dt + σu² dt³/3) I, -(σu² dt²/2) I], [-(σu² dt²/2) I, σu² dt I]]

(Q is exact for the isotropic σv term and to O(|ŵ| dt) for the σu terms, the usual
approximation of the book.)  The attitude is propagated by the exact rotation ``q ⊗ Exp(ŵ dt)``.
After an update ``δx̂ = K ν`` the attitude error is folded into the reference,
``R̂⁺ = R̂ Exp(δθ̂)``, ``b̂⁺ = b̂ + Δb̂``, and reset to zero; to first order the covariance of the
new error is ``G P Gᵀ`` with ``G = blockdiag(I - ½[δθ̂×], I)`` (Mueller et al. 2017).

Every function accepts either one filter (q (4,), b (3,), P (6, 6), ...) or a batch with one
leading axis (q (N, 4), b (N, 3), P (N, 6, 6), ...); noise parameters and ``R`` may be shared
((3, 3)) or per filter ((N, 3, 3)).  Bad input raises ``ValueError``.

Quaternion algebra is done by :mod:`gnc.quat` on plain arrays (same conventions and results
as scipy's ``Rotation`` to rounding, at a fraction of its per-call cost); input quaternions are
normalised, as ``Rotation.from_quat`` did.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from gnc import quat

__all__ = ["error_state", "mekf_init", "mekf_propagate", "mekf_transition", "mekf_update"]

FloatArray = npt.NDArray[np.float64]

# Below this |ŵ| dt (rad) the coefficients of Φ come from their Taylor series.
_PHI_SERIES_RAD = 1e-2


def _arr(name: str, value: npt.ArrayLike, tail: tuple[int, ...], batch: tuple[int, ...] | None
         ) -> FloatArray:
    """A finite float array of shape ``batch + tail`` (batch () or (N,); None = either)."""
    arr = np.array(value, dtype=float)
    ok_tail = arr.shape[arr.ndim - len(tail):] == tail and arr.ndim - len(tail) in (0, 1)
    if not ok_tail or (batch is not None and arr.shape[: arr.ndim - len(tail)] not in ((), batch)):
        raise ValueError(f"{name} has shape {arr.shape}; expected {tail} or (N, *{tail})")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite")
    return arr


def _quat(name: str, value: npt.ArrayLike, batch: tuple[int, ...] | None) -> FloatArray:
    """The unit quaternion(s) along a finite, non-zero (4,) or batch + (4,) input."""
    q = _arr(name, value, (4,), batch)
    if q.ndim == 1:  # one filter: float arithmetic, numpy's reductions cost µs each
        norm = math.hypot(*q.tolist())
        if norm < 1e-12:
            raise ValueError(f"{name} contains a zero quaternion")
        return q / norm
    norms = np.sqrt(np.sum(q * q, axis=-1, keepdims=True))
    if (norms < 1e-12).any():
        raise ValueError(f"{name} contains a zero quaternion")
    out: FloatArray = q / norms
    return out


def _skew(v: FloatArray) -> FloatArray:
    """Cross-product matrices [v×], (..., 3) -> (..., 3, 3)."""
    if v.ndim == 1:
        x, y, z = v.tolist()
        return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _check_cov(name: str, value: npt.ArrayLike, n: int, batch: tuple[int, ...]) -> FloatArray:
    """A finite symmetric positive definite covariance of shape (n, n) or batch + (n, n)."""
    m = _arr(name, value, (n, n), batch)
    if np.abs(m - np.swapaxes(m, -1, -2)).max() > 1e-9 * np.abs(m).max():
        raise ValueError(f"{name} must be symmetric")
    try:
        np.linalg.cholesky(m)
    except np.linalg.LinAlgError as exc:
        raise ValueError(f"{name} must be positive definite") from exc
    return m


def _noise_params(dt: float, sigma_v: float, sigma_u: float) -> None:
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be positive and finite, got {dt!r} s")
    for name, s in (("sigma_v", sigma_v), ("sigma_u", sigma_u)):
        if not (math.isfinite(s) and s >= 0.0):
            raise ValueError(f"{name} must be >= 0 and finite, got {s!r}")


def _phi_coefficients(x: float | FloatArray) -> tuple[Any, Any, Any]:
    """``sin(x)/x``, ``(1 - cos x)/x²`` and ``(x - sin x)/x³`` of ``x = |ŵ| dt >= 0`` (rad).

    By their Taylor series below 1e-2 rad (truncation error < 1e-16), where the closed forms
    lose digits to cancellation.  ``x`` a float (one filter: math functions) or an array
    (elementwise).
    """
    x2 = x * x
    series = (1.0 - x2 / 6.0 + x2 * x2 / 120.0, 0.5 - x2 / 24.0 + x2 * x2 / 720.0,
              1.0 / 6.0 - x2 / 120.0 + x2 * x2 / 5040.0)
    if isinstance(x, float):
        if x < _PHI_SERIES_RAD:
            return series
        sin_x, cos_x = math.sin(x), math.cos(x)
        return sin_x / x, (1.0 - cos_x) / (x * x), (x - sin_x) / (x * x * x)
    small = x < _PHI_SERIES_RAD
    xs = np.where(small, 1.0, x)
    sin_a, cos_a = np.sin(xs), np.cos(xs)
    closed = (sin_a / xs, (1.0 - cos_a) / (xs * xs), (xs - sin_a) / (xs * xs * xs))
    s0, c1, c2 = (np.where(small, a, b) for a, b in zip(series, closed, strict=True))
    return s0, c1, c2


def mekf_transition(
    w_hat: npt.ArrayLike, dt: float, sigma_v: float, sigma_u: float
) -> tuple[FloatArray, FloatArray]:
    """Discrete error-state transition Φ (..., 6, 6) and process noise Q (6, 6) over ``dt``.

    Args:
        w_hat: bias-corrected body rate held over the interval, (3,) or (N, 3), rad/s.
        dt: interval, s.
        sigma_v: gyro angle random walk, rad/√s.
        sigma_u: gyro bias rate random walk, rad/s^1.5.
    """
    _noise_params(dt, sigma_v, sigma_u)
    w = _arr("w_hat", w_hat, (3,), None)
    norm = np.sqrt((w * w).sum(axis=-1))
    # one filter: plain floats (numpy's per-call overhead on (1, 1) arrays dominated here)
    s0, c1, c2 = _phi_coefficients(float(norm) * dt if w.ndim == 1 else norm[..., None, None] * dt)
    W = _skew(w)
    W2 = W @ W
    eye = np.eye(3)
    phi = np.zeros(w.shape[:-1] + (6, 6))
    phi[..., :3, :3] = eye - dt * s0 * W + dt**2 * c1 * W2
    phi[..., :3, 3:] = -dt * eye + dt**2 * c1 * W - dt**3 * c2 * W2
    phi[..., 3:, 3:] = eye
    q = np.zeros((6, 6))
    q[:3, :3] = (sigma_v**2 * dt + sigma_u**2 * dt**3 / 3.0) * eye
    q[:3, 3:] = q[3:, :3] = -0.5 * sigma_u**2 * dt**2 * eye
    q[3:, 3:] = sigma_u**2 * dt * eye
    return phi, q


def mekf_init(
    q_meas: npt.ArrayLike,
    att_cov: npt.ArrayLike,
    bias_sigma: float,
    b0: npt.ArrayLike | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Initial (q, b, P) from a first attitude measurement.

    Args:
        q_meas: measured R_eci_body, scalar-last, (4,) or (N, 4).
        att_cov: covariance of the initial attitude error, body axes, (3, 3) or (N, 3, 3), rad²
            (e.g. the star tracker's R).
        bias_sigma: 1σ of the initial bias error per axis, rad/s (> 0).
        b0: initial bias estimate, (3,) or (N, 3), rad/s (default zero).
    """
    q = _quat("q_meas", q_meas, None)
    batch = q.shape[:-1]
    if not (math.isfinite(bias_sigma) and bias_sigma > 0.0):
        raise ValueError(f"bias_sigma must be positive and finite, got {bias_sigma!r}")
    cov = _check_cov("att_cov", att_cov, 3, batch)
    b = np.zeros(batch + (3,))
    if b0 is not None:
        b += _arr("b0", b0, (3,), batch)
    P = np.zeros(batch + (6, 6))
    P[..., :3, :3] = cov
    P[..., 3:, 3:] = bias_sigma**2 * np.eye(3)
    return quat.canonical(q), b, P


def mekf_propagate(
    q: npt.ArrayLike,
    b: npt.ArrayLike,
    P: npt.ArrayLike,
    w_meas: npt.ArrayLike,
    dt: float,
    sigma_v: float,
    sigma_u: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Time update over ``dt`` with the average measured rate ``w_meas``.

    Args:
        q: attitude estimate R_eci_body, scalar-last, (4,) or (N, 4).
        b: gyro bias estimate, body axes, (3,) or (N, 3), rad/s.
        P: error covariance, (6, 6) or (N, 6, 6) (rad², rad²/s, rad²/s²).
        w_meas: gyro output averaged over the interval, body axes, (3,) or (N, 3), rad/s.
        dt: interval, s.
        sigma_v: gyro angle random walk, rad/√s.
        sigma_u: gyro bias rate random walk, rad/s^1.5.

    Returns:
        (q, b, P) at the end of the interval.
    """
    qa = _quat("q", q, None)
    batch = qa.shape[:-1]
    ba = _arr("b", b, (3,), batch)
    Pa = _arr("P", P, (6, 6), batch)
    w_hat = _arr("w_meas", w_meas, (3,), batch) - ba
    phi, Q = mekf_transition(w_hat, dt, sigma_v, sigma_u)
    q_new = quat.mul(qa, quat.exp(w_hat * dt))
    P_new = phi @ Pa @ np.swapaxes(phi, -1, -2) + Q
    P_sym = 0.5 * (P_new + np.swapaxes(P_new, -1, -2))
    return quat.canonical(q_new), ba * np.ones(batch + (3,)), P_sym


def mekf_update(
    q: npt.ArrayLike,
    b: npt.ArrayLike,
    P: npt.ArrayLike,
    q_meas: npt.ArrayLike,
    R: npt.ArrayLike,
) -> tuple[FloatArray, FloatArray, FloatArray, float | FloatArray]:
    """Measurement update with a star-tracker attitude (Joseph form, then reset).

    Args:
        q, b, P: prior as in :func:`mekf_propagate`.
        q_meas: measured R_eci_body, scalar-last, (4,) or (N, 4) (either sign).
        R: covariance of the measurement's small-angle error, body axes, (3, 3) or (N, 3, 3),
            rad².

    Returns:
        (q, b, P, nis) -- the posterior and the normalised innovation squared ``νᵀ S⁻¹ ν``
        (χ² with 3 dof when the filter is consistent): a float for one filter, (N,) for a batch.
    """
    qa = _quat("q", q, None)
    batch = qa.shape[:-1]
    ba = _arr("b", b, (3,), batch)
    Pa = _arr("P", P, (6, 6), batch)
    qm = _quat("q_meas", q_meas, batch)
    Ra = _check_cov("R", R, 3, batch)
    nu = quat.log(quat.mul(quat.conj(qa), qm))
    S = Pa[..., :3, :3] + Ra
    try:
        S_inv = np.linalg.inv(S)
    except np.linalg.LinAlgError as exc:
        raise ValueError("innovation covariance is singular") from exc
    K = Pa[..., :, :3] @ S_inv
    dx = np.einsum("...ij,...j->...i", K, nu)
    I_KH = np.zeros(batch + (6, 6))
    I_KH[..., :, :3] = -K
    I_KH += np.eye(6)
    P_new = I_KH @ Pa @ np.swapaxes(I_KH, -1, -2) + K @ Ra @ np.swapaxes(K, -1, -2)
    G = np.zeros(batch + (6, 6))
    G[..., :3, :3] = -0.5 * _skew(dx[..., :3])
    G += np.eye(6)
    P_new = G @ P_new @ np.swapaxes(G, -1, -2)
    q_new = quat.mul(qa, quat.exp(dx[..., :3]))
    nis_arr = np.einsum("...i,...ij,...j->...", nu, S_inv, nu)
    nis: float | FloatArray = float(nis_arr) if nis_arr.ndim == 0 else nis_arr
    P_sym = 0.5 * (P_new + np.swapaxes(P_new, -1, -2))
    return quat.canonical(q_new), ba + dx[..., 3:], P_sym, nis


def error_state(
    q_est: npt.ArrayLike, b_est: npt.ArrayLike, q_true: npt.ArrayLike, b_true: npt.ArrayLike
) -> FloatArray:
    """The filter's error state ``[Log(R̂ᵀ R_true), b_true - b̂]``, (6,) or (N, 6) (rad, rad/s)."""
    qe = _quat("q_est", q_est, None)
    batch = qe.shape[:-1]
    dtheta = quat.log(quat.mul(quat.conj(qe), _quat("q_true", q_true, batch)))
    db = _arr("b_true", b_true, (3,), batch) - _arr("b_est", b_est, (3,), batch)
    out: FloatArray = np.concatenate(np.broadcast_arrays(dtheta, db), axis=-1)
    return out
