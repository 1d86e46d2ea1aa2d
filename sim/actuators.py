"""Actuator models of the sim (the hardware stand-in): thrusters and reaction wheels.

Both classes are vectorised over N spacecraft (first axis of every array, N = 1..64) and hold
commands constant over one tick of length ``dt``.  Every random draw comes from the spacecraft's
own ``numpy.random.Generator`` (``rngs[i]`` for spacecraft i), and each generator is drawn the
same number of times every tick whatever the command, so one spacecraft's noise never depends on
the others' or on its own command history.

Fault hooks (written by fault injection, read every tick): ``WheelArray.torque_scale`` /
``WheelArray.torque_bias_nm``.  A thruster leak acts whether or not the thrusters fire, so it
lives in ``sim.hardware.ObserverHardware.force_bias_body``, not here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from sim import kernels
from sim.sensors import as_generators

__all__ = ["ThrusterBank", "WheelArray", "accel_lvlh"]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def _check_dt(dt: float) -> None:
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be positive and finite, got {dt!r} s")


def _per_axis_limit(name: str, value: npt.ArrayLike) -> FloatArray:
    """A positive finite limit, scalar or per body axis, as a (3,) array."""
    arr = np.broadcast_to(np.array(value, dtype=float), (3,)).copy()
    if not (np.all(np.isfinite(arr)) and np.all(arr > 0.0)):
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return arr


def _rows(name: str, value: npt.ArrayLike, n: int) -> FloatArray:
    """A finite (n, 3) array (a single (3,) row is broadcast to all spacecraft)."""
    arr = np.array(value, dtype=float)
    if arr.shape == (3,):
        arr = np.broadcast_to(arr, (n, 3)).copy()
    if arr.shape != (n, 3):
        raise ValueError(f"{name} must have shape ({n}, 3) or (3,), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr!r}")
    return arr


class ThrusterBank:
    """Body-fixed thruster pairs on ±x, ±y, ±z of N spacecraft.

    Per tick and per spacecraft, the commanded body force ``F_cmd`` (N, held for the whole tick
    ``dt``) is realised axis by axis:

    1. saturation: ``F = clip(F_cmd, -f_max, f_max)``;
    2. minimum impulse bit (MIB), impulse ``I = |F| dt``:
       ``mib_rounding="deadband"`` (default) -- ``I < MIB`` is not fired (F = 0), ``I >= MIB``
       is fired as commanded (pulse-width modulation resolves impulses above one MIB);
       ``mib_rounding="nearest"`` -- ``I < MIB/2`` is not fired, ``MIB/2 <= I < MIB`` fires one
       MIB (``|F| = MIB/dt``, capped at f_max), ``I >= MIB`` as commanded;
    3. multiplicative noise on each fired axis: ``F *= max(0, 1 + noise_frac * e)``,
       e ~ N(0, 1) (three draws per spacecraft per tick, fired or not).

    Accounting per spacecraft: ``impulse_ns`` += sum over axes of ``|F_realised| dt`` (the
    propellant-relevant total impulse) and ``pulses`` += number of axes fired in the tick.
    """

    def __init__(
        self,
        f_max_n: npt.ArrayLike,
        min_impulse_ns: float,
        noise_frac: float,
        rngs: Sequence[np.random.Generator],
        mib_rounding: Literal["deadband", "nearest"] = "deadband",
    ) -> None:
        """Create the bank.

        Args:
            f_max_n: maximum force per axis, N (scalar or (3,) per body axis).
            min_impulse_ns: minimum impulse bit, N·s (>= 0).
            noise_frac: 1σ multiplicative force noise as a fraction of the realised force (>= 0).
            rngs: one generator per spacecraft; N = len(rngs).
            mib_rounding: how impulses below one MIB are treated (see the class docstring).
        """
        self._f_max = _per_axis_limit("f_max_n", f_max_n)
        if not (math.isfinite(min_impulse_ns) and min_impulse_ns >= 0.0):
            raise ValueError(f"min_impulse_ns must be >= 0 and finite, got {min_impulse_ns!r}")
        if not (math.isfinite(noise_frac) and noise_frac >= 0.0):
            raise ValueError(f"noise_frac must be >= 0 and finite, got {noise_frac!r}")
        if mib_rounding not in ("deadband", "nearest"):
            raise ValueError(f"mib_rounding must be 'deadband' or 'nearest', got {mib_rounding!r}")
        self._mib = float(min_impulse_ns)
        self._noise = float(noise_frac)
        self._rounding = mib_rounding
        self._rngs = as_generators(rngs)
        n = len(self._rngs)
        self._impulse: FloatArray = np.zeros(n)
        self._pulses: IntArray = np.zeros(n, dtype=np.int64)

    @property
    def n(self) -> int:
        """Number of spacecraft N."""
        return len(self._rngs)

    @property
    def f_max_n(self) -> FloatArray:
        """Maximum force per body axis (3,), N."""
        return self._f_max.copy()

    @property
    def impulse_ns(self) -> FloatArray:
        """Total impulse used so far per spacecraft (N,), N·s."""
        return self._impulse.copy()

    @property
    def pulses(self) -> IntArray:
        """Number of commanded axis firings so far per spacecraft (N,)."""
        return self._pulses.copy()

    def fire(self, force_cmd_body: npt.ArrayLike, dt: float) -> FloatArray:
        """Realise one tick of commanded body forces.

        Args:
            force_cmd_body: commanded force, body axes (N, 3), N, held for ``dt``.
            dt: firing duration, s (normally the tick; the impulse is ``|F| dt``).

        Returns:
            The realised body force (N, 3), N, to apply for ``dt``.
        """
        _check_dt(dt)
        f = np.clip(_rows("force_cmd_body", force_cmd_body, self.n), -self._f_max, self._f_max)
        impulse = np.abs(f) * dt
        if self._rounding == "nearest":
            bump = (impulse >= 0.5 * self._mib) & (impulse < self._mib)
            f = np.where(bump, np.sign(f) * np.minimum(self._mib / dt, self._f_max), f)
            fired = impulse >= 0.5 * self._mib
        else:
            fired = impulse >= self._mib
        fired &= f != 0.0
        e = np.stack([g.standard_normal(3) for g in self._rngs])
        f = np.where(fired, f * np.maximum(0.0, 1.0 + self._noise * e), 0.0)
        self._impulse += np.abs(f).sum(axis=1) * dt
        self._pulses += fired.sum(axis=1)
        return f


def accel_lvlh(
    force_body: npt.ArrayLike, r_lvlh_body: Rotation, mass_kg: npt.ArrayLike
) -> FloatArray:
    """Acceleration in LVLH of body-axis forces: ``a = R_lvlh_body F / m``.

    Args:
        force_body: body-axis forces (N, 3) (or (3,) with a single rotation), N.
        r_lvlh_body: truth attitudes w.r.t. LVLH (body -> LVLH), a Rotation (stack of N or single).
        mass_kg: spacecraft mass(es), kg, scalar or (N,); positive.

    Returns:
        LVLH accelerations, same leading shape as ``force_body``, m/s².
    """
    f = np.array(force_body, dtype=float)
    m = np.array(mass_kg, dtype=float)
    if f.shape[-1:] != (3,) or f.ndim > 2 or not np.all(np.isfinite(f)):
        raise ValueError(f"force_body must be finite with shape (N, 3) or (3,), got {f.shape}")
    if not (np.all(np.isfinite(m)) and np.all(m > 0.0)) or m.ndim > 1:
        raise ValueError(f"mass_kg must be positive and finite (scalar or (N,)), got {mass_kg!r}")
    a: FloatArray = r_lvlh_body.apply(f)
    return a / (m[..., None] if m.ndim == 1 else m)


class WheelArray:
    """Three reaction wheels along the body axes of each of N spacecraft.

    The command is the torque on the body ``tau_cmd`` (N·m); the wheels take ``h_dot = -tau``.
    Per tick, per spacecraft and axis, with the wheel momentum ``h`` at the start of the tick:

    1. fault hooks: ``tau = torque_scale * tau_cmd + torque_bias_nm`` (default 1 and 0);
    2. motor torque limit: ``tau = clip(tau, -tau_max, tau_max)``;
    3. momentum saturation, applied to the tick as a whole: the torque is constant over the tick,
       so the momentum at the end is ``h - tau dt``; it is clipped into
       ``[min(-h_max, h), max(h_max, h)]`` and the torque is recomputed from the clipped end value,
       ``tau = (h - h_end) / dt``.  Hence a wheel at its limit gets zero torque in the direction
       that would grow it, a wheel that would cross the limit within the tick gets the (smaller)
       constant torque that brings it exactly to the limit at the end of the tick, unloading is
       never restricted, and a wheel already beyond the limit is not forced back.

    Integrated with :class:`sim.attitude.AttitudeTruth` (which holds the torque constant over the
    tick), ``|h|`` therefore never exceeds ``h_max`` on an axis that started within it.
    """

    def __init__(self, n: int, tau_max_nm: npt.ArrayLike, h_max_nms: npt.ArrayLike,
                 compiled: bool = True) -> None:
        """Create the wheel arrays.

        Args:
            n: number of spacecraft N (>= 1).
            tau_max_nm: motor torque limit per wheel, N·m (scalar or (3,)).
            h_max_nms: momentum limit per wheel, N·m·s (scalar or (3,)).
            compiled: :meth:`realise` on :func:`sim.kernels.realise_wheel_torque` (the same
                bits); False runs the numpy reference.
        """
        self.compiled = compiled
        if int(n) != n or n < 1:
            raise ValueError(f"n must be a positive integer, got {n!r}")
        self._n = int(n)
        self._tau_max = _per_axis_limit("tau_max_nm", tau_max_nm)
        self._h_max = _per_axis_limit("h_max_nms", h_max_nms)
        self._scale: FloatArray = np.ones((self._n, 3))
        self._bias: FloatArray = np.zeros((self._n, 3))

    @property
    def n(self) -> int:
        """Number of spacecraft N."""
        return self._n

    @property
    def h_max_nms(self) -> FloatArray:
        """Momentum limit per body axis (3,), N·m·s."""
        return self._h_max.copy()

    @property
    def tau_max_nm(self) -> FloatArray:
        """Torque limit per body axis (3,), N·m."""
        return self._tau_max.copy()

    @property
    def torque_scale(self) -> FloatArray:
        """Per-axis torque scale factor (N, 3) (fault hook; 1 = nominal, 0 = dead wheel)."""
        return self._scale.copy()

    @torque_scale.setter
    def torque_scale(self, value: npt.ArrayLike) -> None:
        self._scale = _rows("torque_scale", value, self._n)

    @property
    def torque_bias_nm(self) -> FloatArray:
        """Per-axis additive torque bias (N, 3), N·m (fault hook)."""
        return self._bias.copy()

    @torque_bias_nm.setter
    def torque_bias_nm(self, value: npt.ArrayLike) -> None:
        self._bias = _rows("torque_bias_nm", value, self._n)

    def realise(self, tau_cmd_body: npt.ArrayLike, h: npt.ArrayLike, dt: float) -> FloatArray:
        """Torque on the body realised over one tick.

        Args:
            tau_cmd_body: commanded torque on the body, body axes (N, 3), N·m.
            h: wheel momenta at the start of the tick, body axes (N, 3), N·m·s.
            dt: tick length, s.

        Returns:
            The realised torque on the body (N, 3), N·m, constant over the tick.
        """
        _check_dt(dt)
        cmd, h0 = _rows("tau_cmd_body", tau_cmd_body, self._n), _rows("h", h, self._n)
        if self.compiled:
            out_fast: FloatArray = kernels.realise_wheel_torque(
                cmd, h0, self._scale, self._bias, self._tau_max, self._h_max, float(dt))
            return out_fast
        tau = self._scale * cmd + self._bias
        tau = np.clip(tau, -self._tau_max, self._tau_max)
        h_end = h0 - tau * dt
        h_lim = np.clip(h_end, np.minimum(-self._h_max, h0), np.maximum(self._h_max, h0))
        # Recompute only the limited axes, so unlimited torques pass bit-exact.
        out: FloatArray = np.where(h_lim != h_end, (h0 - h_lim) / dt, tau)
        return out
