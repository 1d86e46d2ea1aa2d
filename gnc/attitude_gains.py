"""The attitude loop's gain design: quaternion-feedback gains (kp, kd) from a second-order
closed-loop settling time and damping, for the flight tracking law
(``fsw.lib.attitude_control.tracking_torque``, whose module docstring gives the closed loop).

Shared: the sim sizes a pointing-actuator fault with the same design (``faults/hardware.py``: the
torque bias at which the nominal loop settles a stated angle off its target).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["AttitudeGains", "gains_for"]


@dataclass(frozen=True)
class AttitudeGains:
    """Gains of :func:`tracking_torque`.

    Attributes:
        kp: attitude gain, 1/s² (acts on the quaternion vector part δq_v ≈ δθ/2).
        kd: rate gain, 1/s.
        w_max_radps: limit on the error-response rate ``|ω_c|``, rad/s, or None for
            no rate limit.
    """

    kp: float
    kd: float
    w_max_radps: float | None = None

    def __post_init__(self) -> None:
        for name in ("kp", "kd"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0.0):
                raise ValueError(f"AttitudeGains.{name} must be positive and finite, got {v!r}")
        w = self.w_max_radps
        if w is not None and not (isinstance(w, (int, float)) and math.isfinite(w) and w > 0.0):
            raise ValueError(f"AttitudeGains.w_max_radps must be positive and finite, got {w!r}")

    @property
    def natural_frequency_radps(self) -> float:
        """ω_n = sqrt(kp/2) of the small-angle error dynamics, rad/s."""
        return math.sqrt(0.5 * self.kp)

    @property
    def damping(self) -> float:
        """Damping ratio ζ = kd / (2 ω_n) of the small-angle error dynamics."""
        return self.kd / (2.0 * self.natural_frequency_radps)

    @classmethod
    def gains_for(
        cls,
        settling_time_s: float,
        damping: float = 0.9,
        w_max_radps: float | None = None,
    ) -> AttitudeGains:
        """Same as the module-level :func:`gains_for`."""
        return gains_for(settling_time_s, damping, w_max_radps)


def gains_for(
    settling_time_s: float,
    damping: float = 0.9,
    w_max_radps: float | None = None,
) -> AttitudeGains:
    """Gains from a second-order closed-loop design.

    For small errors ``δq_v ≈ δθ/2`` and the closed loop (see the module
    docstring) is, per axis, ``δθ̈ + kd δθ̇ + (kp/2) δθ = 0``: a second-order
    system with ``ω_n² = kp/2`` and ``2 ζ ω_n = kd``.  The 2 % settling time of
    its slowest mode is ``t_s = 4/σ`` with decay rate ``σ = ζ ω_n`` for
    ``ζ ≤ 1`` and ``σ = ω_n (ζ − sqrt(ζ² − 1))`` for ``ζ > 1`` (Ogata, *Modern
    Control Engineering*, 5th ed., Sec. 5-3).  Hence
    ``ω_n = 4 / (t_s · σ/ω_n)``, ``kp = 2 ω_n²``, ``kd = 2 ζ ω_n``.  The settling
    time refers to the linear (small-error) regime; large slews are further
    limited by ``w_max_radps`` and the torque limit.

    Args:
        settling_time_s: 2 % settling time of the small-error response, s (> 0).
        damping: damping ratio ζ (> 0).
        w_max_radps: rate limit of the error response, rad/s, or None.

    Returns:
        The gains.
    """
    ts = float(settling_time_s)
    zeta = float(damping)
    if not (math.isfinite(ts) and ts > 0.0):
        raise ValueError(f"settling_time_s must be positive and finite, got {settling_time_s!r}")
    if not (math.isfinite(zeta) and zeta > 0.0):
        raise ValueError(f"damping must be positive and finite, got {damping!r}")
    decay_per_wn = zeta if zeta <= 1.0 else zeta - math.sqrt(zeta * zeta - 1.0)
    wn = 4.0 / (ts * decay_per_wn)
    return AttitudeGains(kp=2.0 * wn * wn, kd=2.0 * zeta * wn, w_max_radps=w_max_radps)
