"""Truth rigid-body attitude dynamics of N spacecraft with three reaction wheels each.

This is the simulator's *truth* attitude model (the flight software never imports it).

Conventions (fixed for the project):

* attitude ``R_eci_body`` (body vectors -> ECI vectors), stored as a unit quaternion in scipy's
  scalar-last convention ``[x, y, z, w]``;
* ``w`` -- body angular velocity with respect to inertial space, body axes, rad/s;
* ``h`` -- reaction wheel angular momentum, body axes (three wheels along the body axes), N·m·s;
* ``tau_body`` -- the torque the wheels exert on the body, N·m; the wheels absorb it as
  ``h_dot = -tau_body``;
* ``J`` -- inertia of the whole spacecraft (wheels included, their spin momentum excluded), kg·m².

Equations of motion (gyrostat with body-fixed wheel axes; Hughes, *Spacecraft Attitude Dynamics*,
2nd ed., Ch. 3; Markley & Crassidis, *Fundamentals of Spacecraft Attitude Determination and
Control*, 2014, Eq. 3.147 and 3.21)::

    J w_dot = -w x (J w + h) + tau_body + tau_ext
    h_dot   = -tau_body
    q_dot   = 1/2 q (x) [w, 0]          (Hamilton product, R_eci_body convention)

so the total angular momentum ``R_eci_body (J w + h)`` changes only with ``tau_ext``.

Integration: classical fixed-step RK4 of the stacked state, vectorised over the spacecraft; the
torques are held constant over each ``step`` call (the 10 Hz tick); the quaternions are
renormalised after every RK4 substep.  The integral of ``w`` over the step is integrated alongside,
which is exactly what a rate-integrating gyro senses (see :attr:`AttitudeTruth.mean_rate`).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from sim import kernels

__all__ = ["AttitudeTruth"]

FloatArray = npt.NDArray[np.float64]


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise cross products of (N, 3) arrays (cheaper than ``np.cross`` for small N)."""
    a2 = np.concatenate((a, a), axis=1)
    b2 = np.concatenate((b, b), axis=1)
    out: FloatArray = a2[:, 1:4] * b2[:, 2:5] - a2[:, 2:5] * b2[:, 1:4]
    return out


def _as_stack(name: str, value: npt.ArrayLike, n: int | None, width: int) -> FloatArray:
    """Validate a finite (N, width) array (a single row (width,) is accepted when N == 1)."""
    arr = np.array(value, dtype=float)
    if arr.ndim == 1 and arr.shape == (width,) and n in (None, 1):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != width or (n is not None and arr.shape[0] != n):
        want = f"({'N' if n is None else n}, {width})"
        raise ValueError(f"{name} must have shape {want}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr!r}")
    return arr


class AttitudeTruth:
    """Coupled rigid-body + wheel momentum + quaternion kinematics truth of N spacecraft.

    Attributes:
        t_s: current time, s (advanced by :meth:`step`).
    """

    def __init__(
        self,
        q0: npt.ArrayLike,
        w0: npt.ArrayLike,
        J: npt.ArrayLike,
        h0: npt.ArrayLike,
        t0_s: float = 0.0,
        compiled: bool = True,
    ) -> None:
        """Initialise the truth state.

        Args:
            q0: initial attitudes R_eci_body, scalar-last quaternions (N, 4); normalised here
                (a zero or non-finite quaternion is an error).
            w0: initial body rates w.r.t. inertial, body axes (N, 3), rad/s.
            J: inertia, kg·m², (3, 3) shared by all or (N, 3, 3); symmetric positive definite.
            h0: initial wheel momenta, body axes (N, 3), N·m·s.
            t0_s: initial time, s.
            compiled: integrate with the compiled kernel (:func:`sim.kernels.attitude_rk4`);
                False runs the numpy reference (:meth:`_rk4_numpy`).
        """
        self.compiled = compiled
        q = _as_stack("q0", q0, None, 4)
        norms = np.linalg.norm(q, axis=1)
        if np.any(norms < 1e-12):
            raise ValueError("q0 contains a zero quaternion")
        n = q.shape[0]
        self._q: FloatArray = q / norms[:, None]
        self._w: FloatArray = _as_stack("w0", w0, n, 3)
        self._h: FloatArray = _as_stack("h0", h0, n, 3)
        inertia = np.array(J, dtype=float)
        if inertia.shape == (3, 3):
            inertia = np.broadcast_to(inertia, (n, 3, 3)).copy()
        if inertia.shape != (n, 3, 3) or not np.all(np.isfinite(inertia)):
            raise ValueError(
                f"J must be finite with shape (3, 3) or ({n}, 3, 3), got {inertia.shape}")
        if not np.allclose(inertia, np.swapaxes(inertia, 1, 2), rtol=1e-12, atol=0.0):
            raise ValueError("J must be symmetric")
        if np.any(np.linalg.eigvalsh(inertia) <= 0.0):
            raise ValueError("J must be positive definite")
        self._J: FloatArray = inertia
        self._Jinv: FloatArray = np.linalg.inv(inertia)
        self._mean_rate: FloatArray = self._w.copy()
        self.t_s: float = float(t0_s)

    # ----- state access ---------------------------------------------------

    @property
    def n(self) -> int:
        """Number of spacecraft N."""
        return int(self._q.shape[0])

    @property
    def q(self) -> FloatArray:
        """Attitudes R_eci_body as scalar-last unit quaternions (N, 4) (a copy)."""
        return self._q.copy()

    @property
    def w(self) -> FloatArray:
        """Body angular velocities w.r.t. inertial, body axes (N, 3), rad/s (a copy)."""
        return self._w.copy()

    @property
    def h(self) -> FloatArray:
        """Wheel angular momenta, body axes (N, 3), N·m·s (a copy)."""
        return self._h.copy()

    @property
    def J(self) -> FloatArray:
        """Inertias (N, 3, 3), kg·m² (a copy)."""
        return self._J.copy()

    @property
    def mean_rate(self) -> FloatArray:
        """Body rate averaged over the last :meth:`step` call, ``(1/dt) ∫ w dt`` (N, 3), rad/s.

        This is the true input of a rate-integrating gyro sampled once per step.  Before the
        first step it equals the initial rate.
        """
        return self._mean_rate.copy()

    def r_eci_body(self) -> Rotation:
        """The attitudes as a scipy Rotation stack of length N (body -> ECI)."""
        return Rotation.from_quat(self._q)

    def angular_momentum_eci(self) -> FloatArray:
        """Total angular momentum ``R_eci_body (J w + h)`` (N, 3), N·m·s, in ECI."""
        body = (self._J @ self._w[:, :, None])[:, :, 0] + self._h
        out: FloatArray = self.r_eci_body().apply(body)
        return out

    # ----- dynamics ---------------------------------------------------------

    def _deriv(self, y: FloatArray, tau_total: FloatArray, tau_wheel: FloatArray) -> FloatArray:
        """Time derivative of the stacked state ``y = [q (4), w (3), h (3)]`` (N, 10).

        ``q_dot = 1/2 q (x) [w, 0]`` is the Hamilton product written out for scalar-last
        ``q = [v, s]``: vector part ``(s w + v x w) / 2``, scalar part ``-(v . w) / 2``.
        """
        q, w, h = y[:, 0:4], y[:, 4:7], y[:, 7:10]
        out = np.empty_like(y)
        n = y.shape[0]
        momentum = (self._J @ w[:, :, None])[:, :, 0] + h
        # Both cross products (w x (J w + h) and v x w) in one call.
        cross = _cross(np.concatenate((w, q[:, 0:3])), np.concatenate((momentum, w)))
        out[:, 4:7] = (self._Jinv @ (tau_total - cross[:n])[:, :, None])[:, :, 0]
        out[:, 0:3] = 0.5 * (q[:, 3:4] * w + cross[n:])
        out[:, 3] = -0.5 * (q[:, 0:3] * w).sum(axis=1)
        out[:, 7:10] = -tau_wheel
        return out

    def step(
        self,
        dt: float,
        tau_body: npt.ArrayLike,
        substeps: int = 1,
        tau_ext_body: npt.ArrayLike | None = None,
    ) -> None:
        """Advance by ``dt`` with the torques held constant.

        Args:
            dt: step length, s (> 0).
            tau_body: torque of the wheels on the body, body axes (N, 3), N·m
                (the wheels' momentum changes by ``-tau_body * dt``).
            substeps: number of equal RK4 substeps (>= 1).
            tau_ext_body: optional external torque (disturbance, thrusters), body axes
                (N, 3), N·m.
        """
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be positive and finite, got {dt!r} s")
        if int(substeps) != substeps or substeps < 1:
            raise ValueError(f"substeps must be a positive integer, got {substeps!r}")
        tau = _as_stack("tau_body", tau_body, self.n, 3)
        ext = (np.zeros_like(tau) if tau_ext_body is None
               else _as_stack("tau_ext_body", tau_ext_body, self.n, 3))
        tau_total = tau + ext
        y = np.concatenate((self._q, self._w, self._h), axis=1)
        if self.compiled:
            y, theta = kernels.attitude_rk4(y, self._J, self._Jinv, tau_total, tau, float(dt),
                                            int(substeps))
        else:
            y, theta = self._rk4_numpy(y, tau_total, tau, dt, int(substeps))
        q, w, h = y[:, 0:4].copy(), y[:, 4:7].copy(), y[:, 7:10].copy()
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(w))):
            raise FloatingPointError("attitude truth diverged (non-finite state); reduce dt")
        self._q, self._w, self._h = q, w, h
        self._mean_rate = theta / dt
        self.t_s += dt

    def _rk4_numpy(self, y: FloatArray, tau_total: FloatArray, tau: FloatArray, dt: float,
                   substeps: int) -> tuple[FloatArray, FloatArray]:
        """The reference RK4 (numpy, vectorised over the spacecraft): (y, ∫w dt)."""
        hs = dt / substeps
        theta = np.zeros((y.shape[0], 3))
        for _ in range(substeps):
            k1 = self._deriv(y, tau_total, tau)
            y2 = y + (0.5 * hs) * k1
            k2 = self._deriv(y2, tau_total, tau)
            y3 = y + (0.5 * hs) * k2
            k3 = self._deriv(y3, tau_total, tau)
            y4 = y + hs * k3
            k4 = self._deriv(y4, tau_total, tau)
            # theta_dot = w, so the RK4 slopes of theta are the stage rates (columns 4:7).
            theta += (hs / 6.0) * (y[:, 4:7] + 2.0 * (y2[:, 4:7] + y3[:, 4:7]) + y4[:, 4:7])
            y = y + (hs / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
            y[:, 0:4] /= np.sqrt((y[:, 0:4] ** 2).sum(axis=1, keepdims=True))
        return y, theta
