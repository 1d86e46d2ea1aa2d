"""Linear Kalman filter steps (pure functions).

Discrete model x_{k+1} = Ad x_k + Bd u_k + w_k, w ~ N(0, Qd); measurement z = H x + v, v ~ N(0, R).
The update uses the Joseph form, which keeps P symmetric positive definite under round-off.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


def predict(
    x: FloatArray, P: FloatArray, Ad: FloatArray, Qd: FloatArray,
    Bd: FloatArray | None = None, u: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Time update: propagate the mean and covariance one step."""
    x_new = Ad @ x
    if Bd is not None and u is not None:
        x_new = x_new + Bd @ u
    P_new = Ad @ P @ Ad.T + Qd
    return x_new, 0.5 * (P_new + P_new.T)


def update(
    x: FloatArray, P: FloatArray, z: FloatArray, H: FloatArray, R: FloatArray
) -> tuple[FloatArray, FloatArray, float]:
    """Measurement update (Joseph form).  Returns (x, P, NIS), where the normalized innovation
    squared NIS = νᵀ S⁻¹ ν is chi-square with dim(z) degrees of freedom when the filter is
    consistent."""
    nu = z - H @ x
    S = H @ P @ H.T + R
    K = np.linalg.solve(S, H @ P).T  # = P Hᵀ S⁻¹ (S and P symmetric)
    x_new = x + K @ nu
    I_KH = np.eye(P.shape[0]) - K @ H
    P_new = I_KH @ P @ I_KH.T + K @ R @ K.T
    nis = float(nu @ np.linalg.solve(S, nu))
    return x_new, 0.5 * (P_new + P_new.T), nis


def nees(x_est: FloatArray, P: FloatArray, x_true: FloatArray) -> float:
    """Normalized estimation error squared eᵀ P⁻¹ e (chi-square, dim(x) dof if consistent)."""
    e = x_est - x_true
    return float(e @ np.linalg.solve(P, e))


def diverged(x: FloatArray, P: FloatArray, bounds: FloatArray) -> bool:
    """Whether the filter has left what its messages can carry: a non-finite entry, a state
    component beyond ``bounds`` (per component, the same units as x), a negative variance, or a
    variance beyond ``bounds²``.  A diverged filter restarts from its next measurement."""
    if not (np.isfinite(x).all() and np.isfinite(P).all()):
        return True
    var = np.diag(P)
    return bool((np.abs(x) > bounds).any() or (var < 0.0).any() or (var > bounds**2).any())
