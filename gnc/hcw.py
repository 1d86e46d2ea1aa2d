"""Hill-Clohessy-Wiltshire (HCW) relative motion: the flight model.

Frame (Hill / LVLH, rotating with a circular chief orbit):

* x -- radial, along the chief position vector (m),
* y -- along-track, ``y = z x x`` (m),
* z -- cross-track, along the chief orbital angular momentum (m).

State vector ``[x, y, z, vx, vy, vz]`` in m and m/s, where the velocities are
time derivatives of the coordinates in the rotating frame.  Inputs are
accelerations ``[ax, ay, az]`` in m/s^2 in the same frame.  Angles are in
radians, times in seconds, mean motion ``n`` in rad/s.

Equations of motion (circular chief, linearised two-body gravity)::

    x'' = 3 n^2 x + 2 n y' + ax
    y'' =         - 2 n x' + ay
    z'' =  -n^2 z          + az

The closed-form state-transition matrix is the classical solution (Vallado,
*Fundamentals of Astrodynamics and Applications*, Sec. 6.8; Curtis,
*Orbital Mechanics for Engineering Students*, Sec. 7.5).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from scipy.linalg import expm

from gnc.constants import MU_EARTH_M3_S2, R_EARTH_M

__all__ = [
    "discretize",
    "drift_per_orbit",
    "hcw_matrices",
    "hcw_stm",
    "mean_motion",
    "pro_state",
    "process_noise",
]

FloatArray = npt.NDArray[np.float64]


def _check_n(n: float) -> None:
    if not (n > 0.0 and math.isfinite(n)):
        raise ValueError(f"mean motion must be positive and finite, got {n!r} rad/s")


def mean_motion(altitude_m: float, mu: float = MU_EARTH_M3_S2, r_earth: float = R_EARTH_M) -> float:
    """Mean motion of a circular orbit.

    Args:
        altitude_m: altitude above the equatorial radius, m.
        mu: gravitational parameter, m^3/s^2.
        r_earth: reference (equatorial) radius, m.

    Returns:
        n = sqrt(mu / a^3) in rad/s, with a = r_earth + altitude_m.
    """
    a = r_earth + altitude_m
    if a <= 0.0:
        raise ValueError(f"orbit radius must be positive, got {a!r} m")
    return math.sqrt(mu / a**3)


def hcw_matrices(n: float) -> tuple[FloatArray, FloatArray]:
    """Continuous-time HCW system matrices.

    Args:
        n: chief mean motion, rad/s.

    Returns:
        ``(A, B)``: A is 6x6 (state ``[x, y, z, vx, vy, vz]`` in m, m/s),
        B is 6x3 mapping an acceleration in m/s^2 (LVLH) into the state rate,
        so that ``d/dt s = A s + B u``.
    """
    _check_n(n)
    a = np.zeros((6, 6))
    a[0:3, 3:6] = np.eye(3)
    a[3, 0] = 3.0 * n * n
    a[3, 4] = 2.0 * n
    a[4, 3] = -2.0 * n
    a[5, 2] = -n * n
    b = np.zeros((6, 3))
    b[3:6, :] = np.eye(3)
    return a, b


def hcw_stm(n: float, t: float | npt.ArrayLike) -> FloatArray:
    """Closed-form HCW state-transition matrix Phi(t) = expm(A t).

    Args:
        n: chief mean motion, rad/s.
        t: elapsed time, s.  A scalar gives a 6x6 matrix; an array of shape
            ``S`` gives an array of shape ``S + (6, 6)``.

    Returns:
        Phi(t) such that ``s(t) = Phi(t) @ s(0)``.
    """
    _check_n(n)
    tt = np.asarray(t, dtype=float)
    if tt.size == 1 and math.isfinite(nt := n * float(tt.reshape(()))):
        # one time: Python floats, the same operations (sin, cos: libm's, as numpy's here)
        return _matrix(_stm_rows(n, nt, math.sin(nt), math.cos(nt), 0.0, 1.0), tt.shape)
    nt = n * tt
    return _stacked(_stm_rows(n, nt, np.sin(nt), np.cos(nt), np.zeros_like(nt),
                              np.ones_like(nt)))


Scalar = float | FloatArray
"""A float, or an array of them: the matrices' entries are built by one expression for both."""


def _stm_rows(n: float, nt: Scalar, s: Scalar, c: Scalar, zero: Scalar, one: Scalar
              ) -> tuple[tuple[Scalar, ...], ...]:
    """The entries of Phi(t) (:func:`hcw_stm`) from n (rad/s), n t (rad) and its sine and
    cosine; ``zero``, ``one``: those constants in the entries' type."""
    inv_n = 1.0 / n
    return (
        (4.0 - 3.0 * c, zero, zero, s * inv_n, 2.0 * (1.0 - c) * inv_n, zero),
        (6.0 * (s - nt), one, zero, 2.0 * (c - 1.0) * inv_n, (4.0 * s - 3.0 * nt) * inv_n, zero),
        (zero, zero, c, zero, zero, s * inv_n),
        (3.0 * n * s, zero, zero, c, 2.0 * s, zero),
        (6.0 * n * (c - 1.0), zero, zero, -2.0 * s, 4.0 * c - 3.0, zero),
        (zero, zero, -n * s, zero, zero, c),
    )


def _stacked(rows: tuple[tuple[Scalar, ...], ...]) -> FloatArray:
    """A matrix per time, shape ``S + (rows, columns)``, of entries that are arrays of
    shape ``S``."""
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def _matrix(rows: tuple[tuple[Scalar, ...], ...], shape: tuple[int, ...]) -> FloatArray:
    """The matrix of float entries, shaped ``shape + (rows, columns)`` (``shape``: one
    time's, () or (1,) ...)."""
    m = np.array(rows, dtype=float)
    return m.reshape(shape + m.shape)


def discretize(n: float, dt: float) -> tuple[FloatArray, FloatArray]:
    """Exact zero-order-hold discretisation of the HCW model.

    Computes ``expm([[A, B], [0, 0]] * dt) = [[Ad, Bd], [0, I]]``.

    Args:
        n: chief mean motion, rad/s.
        dt: sample period, s.

    Returns:
        ``(Ad, Bd)``: 6x6 and 6x3, such that
        ``s[k+1] = Ad s[k] + Bd u[k]`` with u (m/s^2) held constant over dt.
    """
    a, b = hcw_matrices(n)
    m = np.zeros((9, 9))
    m[0:6, 0:6] = a
    m[0:6, 6:9] = b
    e = expm(m * dt)
    return e[0:6, 0:6].copy(), e[0:6, 6:9].copy()


def process_noise(n: float, dt: float, q_accel: float) -> FloatArray:
    """Discrete process-noise covariance for white acceleration noise.

    The continuous model is ``d/dt s = A s + B w`` with ``E[w(t) w(s)^T] =
    q_accel * I3 * delta(t - s)``.  The discrete covariance
    ``Qd = int_0^dt Phi(tau) B Qc B^T Phi(tau)^T dtau`` is obtained by Van
    Loan's method (C. F. Van Loan, IEEE TAC 23(3), 1978): with
    ``F = [[-A, B Qc B^T], [0, A^T]] * dt`` and ``E = expm(F)``,
    ``Phi = E22^T`` and ``Qd = Phi @ E12``.  The exponential is evaluated
    for unit density and scaled by ``q_accel`` afterwards (Qd is linear in
    Qc), which keeps the matrix exponential well scaled for any q_accel.
    The result is symmetrised to remove round-off asymmetry.

    For ``n dt << 1`` each axis tends to the double-integrator result
    ``q [[dt^3/3, dt^2/2], [dt^2/2, dt]]``.

    Args:
        n: chief mean motion, rad/s.
        dt: sample period, s (> 0).
        q_accel: acceleration noise power spectral density on each LVLH
            axis, m^2/s^3 (>= 0).

    Returns:
        6x6 symmetric positive semi-definite Qd in m^2, m^2/s, m^2/s^2.
    """
    if not dt > 0.0:
        raise ValueError(f"dt must be positive, got {dt!r} s")
    if not q_accel >= 0.0:
        raise ValueError(f"q_accel must be non-negative, got {q_accel!r} m^2/s^3")
    a, b = hcw_matrices(n)
    f = np.zeros((12, 12))
    f[0:6, 0:6] = -a
    f[0:6, 6:12] = b @ b.T
    f[6:12, 6:12] = a.T
    e = expm(f * dt)
    phi = e[6:12, 6:12].T
    qd = phi @ e[0:6, 6:12]
    qd_sym: FloatArray = 0.5 * (qd + qd.T)
    return q_accel * qd_sym


def pro_state(
    n: float,
    rho_x: float,
    alpha_x: float,
    rho_y: float,
    rho_z: float,
    alpha_z: float,
    t: float = 0.0,
) -> FloatArray:
    """State on a passive relative orbit (PRO), the bounded HCW solution.

    ``x = rho_x sin(n t + alpha_x)``,
    ``y = rho_y + 2 rho_x cos(n t + alpha_x)``,
    ``z = rho_z sin(n t + alpha_z)``, and their time derivatives.  The
    in-plane ellipse is 2:1 along-track to radial, centred at ``(0, rho_y)``,
    and satisfies the no-drift condition ``vy = -2 n x`` at every instant.

    Args:
        n: chief mean motion, rad/s.
        rho_x: radial amplitude, m.
        alpha_x: in-plane phase, rad.
        rho_y: along-track offset of the ellipse centre, m.
        rho_z: cross-track amplitude, m.
        alpha_z: cross-track phase, rad.
        t: time, s.

    Returns:
        ``[x, y, z, vx, vy, vz]`` in m and m/s, shape (6,).
    """
    _check_n(n)
    px = n * t + alpha_x
    pz = n * t + alpha_z
    sx, cx = math.sin(px), math.cos(px)
    sz, cz = math.sin(pz), math.cos(pz)
    return np.array(
        [
            rho_x * sx,
            rho_y + 2.0 * rho_x * cx,
            rho_z * sz,
            n * rho_x * cx,
            -2.0 * n * rho_x * sx,
            n * rho_z * cz,
        ]
    )


def drift_per_orbit(n: float, state: npt.ArrayLike) -> float:
    """Secular along-track drift over one orbit of an HCW state.

    From the closed-form solution, y(t) contains the secular term
    ``-(6 n x0 + 3 vy0) t``; over one period ``2 pi / n`` this is
    ``-6 pi (2 x0 + vy0 / n)``.  Zero exactly when ``vy0 = -2 n x0``.

    Args:
        n: chief mean motion, rad/s.
        state: ``[x, y, z, vx, vy, vz]`` in m and m/s, shape (6,).

    Returns:
        Along-track displacement per orbit, m (negative = trailing).
    """
    _check_n(n)
    s = np.asarray(state, dtype=float)
    if s.shape != (6,):
        raise ValueError(f"state must have shape (6,), got {s.shape}")
    return float(-6.0 * math.pi * (2.0 * s[0] + s[4] / n))


def zoh_matrices(n: float, tau: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Closed-form ZOH transition ``x(tau) = Phi(tau) x(0) + Gamma(tau) u`` (vectorised).

    ``Phi`` is ``hcw_stm``; ``Gamma(tau) = int_0^tau Phi(s) B ds`` integrates the velocity
    columns of the classical HCW STM (Vallado Sec. 6.8) term by term.  With ``th = n tau``,
    ``C1 = 1 - cos th = 2 sin^2(th/2)`` (cancellation-free) and ``S = sin th``::

        Gamma = [[ C1/n^2,        2(th - S)/n^2,            0     ],
                 [ 2(S - th)/n^2, (4 C1 - 1.5 th^2)/n^2,    0     ],
                 [ 0,             0,                        C1/n^2],
                 [ S/n,           2 C1/n,                   0     ],
                 [ -2 C1/n,       (4 S - 3 th)/n,           0     ],
                 [ 0,             0,                        S/n   ]]

    Equal to ``discretize(n, tau)`` to round-off (tested); used for the many intermediate
    times, where a matrix exponential per time would be slow.

    Args:
        n: mean motion, rad/s.
        tau: times since the start of the interval, s, any shape ``S``.

    Returns:
        ``(Phi, Gamma)`` of shapes ``S + (6, 6)`` and ``S + (6, 3)``.
    """
    tt = np.asarray(tau, dtype=float)
    phi = hcw_stm(n, tt)
    if tt.size == 1 and math.isfinite(th := n * float(tt.reshape(()))):
        # one time: Python floats, as in hcw_stm.  sin² as numpy squares it: a scalar's
        # ** 2 is pow(), an array's is x·x (they differ in the last bit for some x)
        half = math.sin(0.5 * th)
        c1 = 2.0 * (half**2 if tt.ndim == 0 else half * half)
        return phi, _matrix(_gamma_rows(n, th, math.sin(th), c1, 0.0), tt.shape)
    th = n * tt
    return phi, _stacked(_gamma_rows(n, th, np.sin(th), 2.0 * np.sin(0.5 * th) ** 2,
                                     np.zeros_like(th)))


def _gamma_rows(n: float, th: Scalar, s: Scalar, c1: Scalar, zero: Scalar
                ) -> tuple[tuple[Scalar, ...], ...]:
    """The entries of Gamma(tau) (:func:`zoh_matrices`, s², s) from n (rad/s), th = n tau
    (rad), sin th and C1 = 2 sin²(th/2); ``zero``: 0 in the entries' type."""
    n2 = n * n
    return (
        (c1 / n2, 2.0 * (th - s) / n2, zero),
        (2.0 * (s - th) / n2, (4.0 * c1 - 1.5 * th * th) / n2, zero),
        (zero, zero, c1 / n2),
        (s / n, 2.0 * c1 / n, zero),
        (-2.0 * c1 / n, (4.0 * s - 3.0 * th) / n, zero),
        (zero, zero, s / n),
    )
