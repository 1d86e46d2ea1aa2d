"""Sensor models of the sim (the hardware stand-in).

Every random draw comes from a ``numpy.random.Generator`` of the spacecraft's own (one per
spacecraft per device), so adding a spacecraft never changes the others' noise.  The attitude
sensors (:class:`Gyro`, :class:`StarTracker`) are vectorised over N spacecraft (first axis).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation


@dataclass
class RelNavSensor:
    """Relative navigation sensor of one observer: true LVLH position and velocity plus white
    Gaussian noise of standard deviations ``sigma_r_m`` (m) and ``sigma_v_mps`` (m/s), drawn from
    the observer's own seeded generator (so adding an observer does not change the others' noise).
    """

    sigma_r_m: float
    sigma_v_mps: float
    rng: np.random.Generator
    bias_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    """Position bias, LVLH, m (fault hook: ``nav_sensor_bias``)."""

    def measure(self, r_true_m: np.ndarray,
                v_true_mps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Noisy (position m, velocity m/s) of a true relative state, plus the bias."""
        noise = self.rng.standard_normal(6)
        return (r_true_m + self.bias_m + self.sigma_r_m * noise[:3],
                v_true_mps + self.sigma_v_mps * noise[3:])


# --------------------------------------------------------------------------
# Attitude sensors
# --------------------------------------------------------------------------

_DEG = math.pi / 180.0
_ARCSEC = _DEG / 3600.0

#: Angle random walk 0.15 deg/sqrt(h) (a STIM300-class MEMS gyro), rad/sqrt(s).
GYRO_ARW_RAD_SQRT_S: float = 0.15 * _DEG / 60.0
#: Rate random walk 3 deg/h/sqrt(h) (the bias wanders a few deg/h per hour), rad/s^1.5.
GYRO_RRW_RAD_S15: float = 3.0 * _DEG / 3600.0 / 60.0
#: Turn-on bias 1σ after ground calibration, 10 deg/h, rad/s.
GYRO_BIAS0_RAD_S: float = 10.0 * _DEG / 3600.0
#: Star tracker 1σ noise (CubeSat class, e.g. 6-10" cross / 40-60" about boresight), arcsec.
STAR_TRACKER_CROSS_ARCSEC: float = 10.0
STAR_TRACKER_ABOUT_ARCSEC: float = 60.0
#: Star tracker output rate, Hz.
STAR_TRACKER_RATE_HZ: float = 5.0


def as_generators(rngs: Sequence[np.random.Generator]) -> list[np.random.Generator]:
    """Validate one ``numpy.random.Generator`` per spacecraft; returns them as a list."""
    out = list(rngs)
    if not out or not all(isinstance(g, np.random.Generator) for g in out):
        raise ValueError(
            "rngs must be a non-empty sequence of numpy.random.Generator, one per spacecraft")
    return out


def _nonneg(name: str, value: float) -> float:
    if not (math.isfinite(value) and value >= 0.0):
        raise ValueError(f"{name} must be >= 0 and finite, got {value!r}")
    return float(value)


class Gyro:
    """Three-axis rate-integrating gyro of N spacecraft (Farrenkopf model), body axes.

    Continuous model (Farrenkopf 1978; Crassidis & Junkins, *Optimal Estimation of Dynamic
    Systems*, 2nd ed., §7.2)::

        w_meas = w_true + b + eta_v,   b_dot = eta_u,
        E[eta_v eta_v^T] = sigma_v^2 I delta(t),  E[eta_u eta_u^T] = sigma_u^2 I delta(t).

    A sample at ``t_{k+1}`` is the average of the measured rate over ``[t_k, t_{k+1}]`` of length
    ``dt`` (the angle increment divided by ``dt``).  Its exact discrete form, used here (Crassidis
    & Junkins §7.2; Crassidis & Markley, "Unscented filtering for spacecraft attitude
    estimation", JGCD 26(4), 2003, simulation section)::

        b_{k+1}   = b_k + sigma_u sqrt(dt) N_u
        w_{k+1}   = wbar_true + (b_{k+1} + b_k) / 2
                    + sqrt(sigma_v^2 / dt + sigma_u^2 dt / 12) N_v

    with ``wbar_true`` the true average rate over the interval (e.g.
    :attr:`sim.attitude.AttitudeTruth.mean_rate`) and N_u, N_v independent standard normal
    3-vectors.  The 1/12 term is the variance of the mean of the bias's Brownian bridge between
    b_k and b_{k+1}; sigma_v^2/dt is that of the mean of the white rate noise.  Per spacecraft and
    sample, six normals are drawn from its own generator (N_v first, then N_u); at construction,
    three more give the initial bias ``b_0 ~ N(0, bias0_sigma^2 I)``.
    """

    def __init__(
        self,
        rngs: Sequence[np.random.Generator],
        sigma_v: float = GYRO_ARW_RAD_SQRT_S,
        sigma_u: float = GYRO_RRW_RAD_S15,
        bias0_sigma: float = GYRO_BIAS0_RAD_S,
    ) -> None:
        """Create the gyros.

        Args:
            rngs: one generator per spacecraft; N = len(rngs).
            sigma_v: angle random walk sigma_v, rad/sqrt(s).
            sigma_u: bias rate random walk sigma_u, rad/s^1.5.
            bias0_sigma: 1σ of the initial bias per axis, rad/s.
        """
        self._rngs = as_generators(rngs)
        self.sigma_v: float = _nonneg("sigma_v", sigma_v)
        self.sigma_u: float = _nonneg("sigma_u", sigma_u)
        b0 = _nonneg("bias0_sigma", bias0_sigma)
        self._bias: np.ndarray = b0 * np.stack([g.standard_normal(3) for g in self._rngs])

    @property
    def n(self) -> int:
        """Number of spacecraft N."""
        return len(self._rngs)

    @property
    def bias(self) -> np.ndarray:
        """True bias at the last sample time (N, 3), rad/s (a copy)."""
        return self._bias.copy()

    def measure(self, w_mean_true: np.ndarray, dt: float) -> np.ndarray:
        """One sample: the measured average rate over the last ``dt`` (N, 3), rad/s.

        Args:
            w_mean_true: true body rate averaged over the interval, body axes (N, 3), rad/s.
            dt: sample interval, s (> 0).
        """
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be positive and finite, got {dt!r} s")
        w = np.array(w_mean_true, dtype=float)
        if w.shape != (self.n, 3) or not np.all(np.isfinite(w)):
            raise ValueError(f"w_mean_true must be finite with shape ({self.n}, 3), got {w.shape}")
        noise = np.stack([g.standard_normal(6) for g in self._rngs])
        b_next = self._bias + self.sigma_u * math.sqrt(dt) * noise[:, 3:]
        sigma_mean = math.sqrt(self.sigma_v**2 / dt + self.sigma_u**2 * dt / 12.0)
        out: np.ndarray = w + 0.5 * (self._bias + b_next) + sigma_mean * noise[:, :3]
        self._bias = b_next
        return out


class StarTracker:
    """Star tracker of N spacecraft measuring R_eci_body, sampled at a fixed rate.

    Noise model: ``R_meas = R_true Exp(v)`` with the small rotation vector ``v`` in body axes,
    ``v ~ N(0, R)``; in the sensor frame ``v`` has 1σ ``sigma_cross`` on the two axes across the
    boresight and ``sigma_about`` about it; the boresight is the body axis ``boresight_axis``
    (0 = x, 1 = y, 2 = z), so ``R`` is diagonal in body axes (:meth:`covariance_body`).  Per
    spacecraft and sample, three normals are drawn from its own generator.  Output quaternions are
    scalar-last with a non-negative scalar part.

    Timing: a sample is due at the first call with ``t_s`` at or after each multiple of
    ``1/rate_hz`` (the first at ``t = 0``); other calls of :meth:`measure` return ``None``.
    """

    def __init__(
        self,
        rngs: Sequence[np.random.Generator],
        sigma_cross_arcsec: float = STAR_TRACKER_CROSS_ARCSEC,
        sigma_about_arcsec: float = STAR_TRACKER_ABOUT_ARCSEC,
        boresight_axis: int = 2,
        rate_hz: float = STAR_TRACKER_RATE_HZ,
    ) -> None:
        """Create the star trackers.

        Args:
            rngs: one generator per spacecraft; N = len(rngs).
            sigma_cross_arcsec: 1σ noise about each axis across the boresight, arcsec.
            sigma_about_arcsec: 1σ noise about the boresight, arcsec.
            boresight_axis: body axis of the boresight, 0, 1 or 2.
            rate_hz: output rate, Hz (> 0).
        """
        self._rngs = as_generators(rngs)
        if boresight_axis not in (0, 1, 2):
            raise ValueError(f"boresight_axis must be 0, 1 or 2, got {boresight_axis!r}")
        if not (math.isfinite(rate_hz) and rate_hz > 0.0):
            raise ValueError(f"rate_hz must be positive and finite, got {rate_hz!r}")
        sigma = np.full(3, _nonneg("sigma_cross_arcsec", sigma_cross_arcsec) * _ARCSEC)
        sigma[boresight_axis] = _nonneg("sigma_about_arcsec", sigma_about_arcsec) * _ARCSEC
        self._sigma_rad = sigma
        self.period_s: float = 1.0 / float(rate_hz)
        self._next_index = 0

    @property
    def n(self) -> int:
        """Number of spacecraft N."""
        return len(self._rngs)

    @property
    def sigma_rad(self) -> np.ndarray:
        """1σ noise about each body axis (3,), rad."""
        return self._sigma_rad.copy()

    def covariance_body(self) -> np.ndarray:
        """Measurement covariance R of the small-angle error in body axes (3, 3), rad²."""
        return np.diag(self._sigma_rad**2)

    def sample(self, r_eci_body: Rotation) -> np.ndarray:
        """Measure now, regardless of timing: noisy R_eci_body quaternions (N, 4), scalar >= 0."""
        count = 1 if r_eci_body.single else len(r_eci_body)
        if count != self.n:
            raise ValueError(f"need a Rotation stack of {self.n} attitudes, got {count}")
        v = np.stack([g.standard_normal(3) for g in self._rngs]) * self._sigma_rad
        q = (r_eci_body * Rotation.from_rotvec(v)).as_quat().reshape(self.n, 4)
        q *= np.where(q[:, 3:4] < 0.0, -1.0, 1.0)
        out: np.ndarray = q
        return out

    def due(self, t_s: float) -> bool:
        """Whether a sample is due at time ``t_s`` (s) (see the class docstring)."""
        if not math.isfinite(t_s):
            raise ValueError(f"t_s must be finite, got {t_s!r}")
        return math.floor(t_s / self.period_s + 1e-9) >= self._next_index

    def measure(self, t_s: float, r_eci_body: Rotation) -> np.ndarray | None:
        """A sample (N, 4) if one is due at time ``t_s`` (s), else ``None``."""
        if not self.due(t_s):
            return None
        self._next_index = math.floor(t_s / self.period_s + 1e-9) + 1
        return self.sample(r_eci_body)
