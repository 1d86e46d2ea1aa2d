"""Passive relative orbits (PROs): parametrisation, conversion, energy matching, distances.

A PRO is the bounded solution of the Hill-Clohessy-Wiltshire (HCW) equations (frame and state as
in :mod:`gnc.hcw`: x radial, y along-track, z cross-track; state ``[x, y, z, vx, vy, vz]`` in
m and m/s).  With ``t`` the absolute mission time in s (t = 0 at mission start) and ``n`` the
chief mean motion in rad/s, the PRO form used throughout the project (REFERENCE.md) is::

    x = rho_x sin(n t + alpha_x)
    y = rho_y + 2 rho_x cos(n t + alpha_x)
    z = rho_z sin(n t + alpha_z)

(Vallado, *Fundamentals of Astrodynamics and Applications*, Sec. 6.8: the HCW solution with the
secular term removed by the no-drift condition ``vy = -2 n x``.)

Everything here is a pure function or a frozen dataclass; nothing touches a bus or a file.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from gnc import hcw
from gnc.checks import finite_array
from gnc.constants import MU_EARTH_M3_S2
from interfaces.contracts.messages import ProElements

__all__ = [
    "Pro",
    "energy_matched_state",
    "min_distance_between",
    "min_distance_to_origin",
    "min_radial_normal_distance",
    "pro_from_state",
    "pro_ring",
]

FloatArray = npt.NDArray[np.float64]

_SAMPLES_PER_PERIOD = 360
"""Phase samples per orbit for the distance searches (before the Brent refinement)."""


@dataclass(frozen=True)
class Pro:
    """A passive relative orbit in the PRO form of REFERENCE.md.

    Attributes:
        rho_x_m: radial amplitude, m (the along-track semi-axis is ``2 rho_x``).
        alpha_x_rad: in-plane phase at t = 0, rad.
        rho_y_m: along-track offset of the ellipse centre, m.
        rho_z_m: cross-track amplitude, m.
        alpha_z_rad: cross-track phase at t = 0, rad.
    """

    rho_x_m: float
    alpha_x_rad: float
    rho_y_m: float
    rho_z_m: float
    alpha_z_rad: float

    def __post_init__(self) -> None:
        values = (self.rho_x_m, self.alpha_x_rad, self.rho_y_m, self.rho_z_m, self.alpha_z_rad)
        if not all(math.isfinite(float(v)) for v in values):
            raise ValueError(f"PRO parameters must be finite, got {values!r}")

    @classmethod
    def of(cls, elements: ProElements) -> Pro:
        """The PRO an assignment's uplinked ``elements`` name (``ProAssignment.pro``)."""
        return cls(elements.rho_x_m, elements.alpha_x_rad, elements.rho_y_m, elements.rho_z_m,
                   elements.alpha_z_rad)

    def state(self, n: float, t: float) -> FloatArray:
        """HCW state on the PRO at absolute time ``t`` (s); ``n`` in rad/s.  Shape (6,)."""
        return hcw.pro_state(n, self.rho_x_m, self.alpha_x_rad, self.rho_y_m, self.rho_z_m,
                             self.alpha_z_rad, t)

    def states(self, n: float, t: npt.ArrayLike) -> FloatArray:
        """HCW states at the absolute times ``t`` (s, shape (T,)); returns shape (T, 6).

        Same formulas as :meth:`state` (the PRO form and its time derivative), vectorised.
        """
        if not (n > 0.0 and math.isfinite(n)):
            raise ValueError(f"mean motion must be positive and finite, got {n!r} rad/s")
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        if tt.ndim != 1:
            raise ValueError(f"t must be a scalar or a 1-D array, got shape {tt.shape}")
        px = n * tt + self.alpha_x_rad
        pz = n * tt + self.alpha_z_rad
        sx, cx, sz, cz = np.sin(px), np.cos(px), np.sin(pz), np.cos(pz)
        out = np.empty((tt.size, 6))
        out[:, 0] = self.rho_x_m * sx
        out[:, 1] = self.rho_y_m + 2.0 * self.rho_x_m * cx
        out[:, 2] = self.rho_z_m * sz
        out[:, 3] = n * self.rho_x_m * cx
        out[:, 4] = -2.0 * n * self.rho_x_m * sx
        out[:, 5] = n * self.rho_z_m * cz
        return out

    def period_s(self, n: float) -> float:
        """Period of the relative motion, ``2 pi / n`` in s (the chief's orbital period)."""
        if not (n > 0.0 and math.isfinite(n)):
            raise ValueError(f"mean motion must be positive and finite, got {n!r} rad/s")
        return 2.0 * math.pi / n

    def positions_at_phase(self, phase_rad: npt.ArrayLike) -> FloatArray:
        """Positions (m) at orbit phases ``n t`` (rad), shape (P, 3).  Independent of ``n``."""
        ph = np.atleast_1d(np.asarray(phase_rad, dtype=float))
        px = ph + self.alpha_x_rad
        return np.stack(
            [
                self.rho_x_m * np.sin(px),
                self.rho_y_m + 2.0 * self.rho_x_m * np.cos(px),
                self.rho_z_m * np.sin(ph + self.alpha_z_rad),
            ],
            axis=-1,
        )


def pro_from_state(
    n: float,
    state: npt.ArrayLike,
    t: float = 0.0,
    *,
    rel_drift_tol: float = 1e-2,
    abs_drift_tol_m: float = 1e-3,
) -> Pro:
    """PRO parameters of a bounded HCW state observed at absolute time ``t``.

    Inverting the PRO form at phase ``phi = n t + alpha``: ``x = rho_x sin(phi_x)`` and
    ``vx = n rho_x cos(phi_x)`` give ``rho_x = hypot(x, vx/n)``, ``phi_x = atan2(x, vx/n)``;
    ``y = rho_y + 2 vx / n`` gives ``rho_y``; z and vz give ``rho_z``, ``phi_z`` the same way.
    The phases are referred back to t = 0 (``alpha = phi - n t``, wrapped to [-pi, pi)).
    ``vy`` is not used: it is fixed by the no-drift condition, which is checked instead.

    Boundedness check: the HCW secular along-track drift per orbit is
    ``6 pi (2 x + vy / n)`` (``hcw.drift_per_orbit``).  The state is accepted when
    ``|drift| <= abs_drift_tol_m + rel_drift_tol * size`` with
    ``size = |(x, y, z, vx/n, vy/n, vz/n)|`` (m), a phase-independent measure of the orbit's
    extent.  The default (1 % of the size per orbit, plus 1 mm) accepts nav-grade estimates and
    energy-matched states (whose HCW drift equivalent is about ``3 pi rho^2 / a``, i.e. 1.4e-6 of
    the size per metre of size at 500 km), and rejects states that leave the PRO visibly within an
    orbit.

    Args:
        n: chief mean motion, rad/s.
        state: HCW state ``[x, y, z, vx, vy, vz]`` at time ``t``, m and m/s.
        t: absolute time of the state, s.
        rel_drift_tol: tolerated drift per orbit as a fraction of the orbit size, dimensionless.
        abs_drift_tol_m: tolerated drift per orbit added to the relative part, m.

    Returns:
        The :class:`Pro` through the state.

    Raises:
        ValueError: bad shapes/values, or the state drifts more than the tolerance.
    """
    s = finite_array("state", state, (6,))
    drift = hcw.drift_per_orbit(n, s)
    size = float(np.linalg.norm(np.concatenate([s[:3], s[3:] / n])))
    if not math.isfinite(t):
        raise ValueError(f"t must be finite, got {t!r}")
    limit = abs_drift_tol_m + rel_drift_tol * size
    if abs(drift) > limit:
        raise ValueError(
            f"state is not on a passive relative orbit: HCW drift {drift:.6g} m per orbit "
            f"(|vy + 2 n x| = {abs(s[4] + 2.0 * n * s[0]):.3g} m/s) exceeds {limit:.3g} m"
        )
    x, y, z, vx, _vy, vz = s
    rho_x = math.hypot(x, vx / n)
    rho_z = math.hypot(z, vz / n)
    alpha_x = _wrap(math.atan2(x, vx / n) - n * t)
    alpha_z = _wrap(math.atan2(z, vz / n) - n * t)
    return Pro(rho_x, alpha_x, y - 2.0 * vx / n, rho_z, alpha_z)


def _wrap(angle: float) -> float:
    """Wrap an angle (rad) to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def energy_matched_state(
    state_lvlh: npt.ArrayLike, chief_radius_m: float, mu: float = MU_EARTH_M3_S2
) -> FloatArray:
    """Adjust ``vy`` so that the deputy's two-body energy equals the circular chief's.

    Two spacecraft with equal two-body specific energy have equal semi-major axes, hence equal
    periods, so their nonlinear relative motion is periodic (no secular drift).  This is the
    energy-matching condition of the paper (Sec. II.B) in its flight-side form.

    Derivation.  With chief radius ``a``, ``n = sqrt(mu / a^3)``, ``omega = (0, 0, n)`` and
    ``r_chief = (a, 0, 0)`` in LVLH, the deputy's position is ``R = (a + x, y, z)`` and its
    inertial velocity in LVLH components is ``V = v_rel + omega x R =
    (vx - n y, vy + n (a + x), vz)``.  Energy matching ``|V|^2 / 2 - mu / |R| = -mu / (2 a)``
    gives ``(vy + n (a + x))^2 = S`` with ``S = 2 mu / |R| - mu / a - (vx - n y)^2 - vz^2``;
    the prograde root ``vy = sqrt(S) - n (a + x)`` is the one near the HCW value ``-2 n x``
    (the other is near ``-2 n a``).  Writing ``vy = -2 n x + delta`` and ``w = n (a - x)``:
    ``(w + delta)^2 = S``, so ``delta = D / (w + sqrt(S))`` with ``D = S - w^2``.  Using
    ``mu = n^2 a^3``, ``|R|^2 = a^2 (1 + eps)``, ``eps = (2 a x + x^2 + y^2 + z^2) / a^2``::

        D = n^2 (2 a^2 g(eps) - 2 x^2 - y^2 - z^2) - (vx - n y)^2 - vz^2,
        g(eps) = (1 + eps)^(-1/2) - 1 + eps/2 = eps^2 (s + 2) / (2 s (1 + s)^2),  s = sqrt(1+eps)

    (the last form follows from ``s - 1 = eps / (1 + s)`` and ``s^2 + s - 2 = (s - 1)(s + 2)``).
    Every term is second order in the relative state and none is a difference of large numbers,
    so ``delta`` (about ``n rho^2 / a``, 1e-7..1e-5 m/s for 10 m..1 km) keeps full relative
    precision instead of being the difference of two ~7.6 km/s numbers.

    Args:
        state_lvlh: HCW state ``[x, y, z, vx, vy, vz]``, m and m/s.
        chief_radius_m: radius ``a`` of the circular chief orbit, m.
        mu: gravitational parameter, m^3/s^2.

    Returns:
        The state with ``vy`` replaced, shape (6,).

    Raises:
        ValueError: bad input, or no real root (relative speed comparable to orbital speed).
    """
    s = finite_array("state", state_lvlh, (6,))
    a = float(chief_radius_m)
    if not (a > 0.0 and math.isfinite(a) and mu > 0.0 and math.isfinite(mu)):
        raise ValueError(f"need a positive chief radius and mu, got a={a!r} m, mu={mu!r} m^3/s^2")
    n = math.sqrt(mu / a**3)
    x, y, z, vx, _vy, vz = s
    a2_eps = 2.0 * a * x + x * x + y * y + z * z  # a^2 eps = |R|^2 - a^2
    eps = a2_eps / (a * a)
    if eps <= -1.0:
        raise ValueError("deputy position at the centre of the Earth")
    sq = math.sqrt(1.0 + eps)
    two_a2_g = a2_eps**2 * (sq + 2.0) / (a * a * sq * (1.0 + sq) ** 2)
    d = n * n * (two_a2_g - 2.0 * x * x - y * y - z * z) - (vx - n * y) ** 2 - vz * vz
    w = n * (a - x)
    big_s = w * w + d
    if not big_s > 0.0 or not w > 0.0:
        raise ValueError("no prograde energy-matching velocity exists for this state")
    delta = d / (w + math.sqrt(big_s))
    out = s.copy()
    out[4] = -2.0 * n * x + delta
    return out


def _dist2_coefficients(pro: Pro) -> tuple[float, complex, complex]:
    """``|r(θ)|² = c0 + Re(a1 e^{iθ}) + Re(a2 e^{2iθ})`` on the PRO (θ = n t), from
    sin²u = (1 − cos 2u)/2 and cos²u = (1 + cos 2u)/2::

        c0 = ρx²/2 + 2ρx² + ρy² + ρz²/2,   a1 = 4 ρy ρx e^{iαx},
        a2 = (3ρx²/2) e^{2iαx} − (ρz²/2) e^{2iαz}.
    """
    rx, ry, rz = pro.rho_x_m, pro.rho_y_m, pro.rho_z_m
    c0 = 2.5 * rx * rx + ry * ry + 0.5 * rz * rz
    a1 = 4.0 * ry * rx * cmath.exp(1j * pro.alpha_x_rad)
    a2 = (1.5 * rx * rx * cmath.exp(2j * pro.alpha_x_rad)
          - 0.5 * rz * rz * cmath.exp(2j * pro.alpha_z_rad))
    return c0, a1, a2


def _trig2_min(c0: float, a1: complex, a2: complex) -> tuple[float, float]:
    """Global minimum ``(value, θ)`` of ``f(θ) = c0 + Re(a1 e^{iθ}) + Re(a2 e^{2iθ})``.

    With z = e^{iθ}, ``f'(θ) = 0`` ⇔ ``2 a2 z⁴ + a1 z³ − conj(a1) z − 2 conj(a2) = 0``: the
    critical points are the roots on the unit circle (``numpy.roots``, companion matrix).  f is
    evaluated at the angle of every root and on a 360-point grid (a guard for near-degenerate
    roots), and the smallest value is returned; a constant f returns θ = 0.
    """
    def f(theta: FloatArray) -> FloatArray:
        z = np.exp(1j * theta)
        return c0 + np.real(a1 * z) + np.real(a2 * z * z)

    coeffs = np.array([2.0 * a2, a1, 0.0, -np.conj(a1), -2.0 * np.conj(a2)])
    scale = max(abs(a1), abs(a2))
    if scale <= 1e-14 * max(abs(c0), 1e-300):
        return float(c0), 0.0
    roots = np.roots(coeffs / scale)
    grid = np.linspace(0.0, 2.0 * math.pi, _SAMPLES_PER_PERIOD, endpoint=False)
    theta = np.concatenate([np.angle(roots), grid]) % (2.0 * math.pi)
    values = f(theta)
    k = int(np.argmin(values))
    return float(values[k]), float(theta[k])


def min_distance_to_origin(pro: Pro, n: float) -> tuple[float, float]:
    """Minimum distance of a PRO from the target (LVLH origin) over one period.

    ``|r|^2`` is a trigonometric polynomial of degree 2 in the phase ``n t``
    (:func:`_dist2_coefficients`); its critical points are the unit-circle roots of a quartic,
    so the minimum is found exactly (:func:`_trig2_min`), in about 0.1 ms.

    Args:
        pro: the orbit.
        n: chief mean motion, rad/s.

    Returns:
        ``(d_min_m, t_at_min_s)`` with the absolute time in ``[0, 2 pi / n)`` s.
    """
    period = pro.period_s(n)
    d2, phase = _trig2_min(*_dist2_coefficients(pro))
    t_min = phase / n
    return math.sqrt(max(d2, 0.0)), (t_min if t_min < period else 0.0)


def _difference(pro_a: Pro, pro_b: Pro) -> Pro:
    """The PRO of the relative motion a - b (HCW is linear, so the difference is a PRO).

    Phasors: ``rho e^{i alpha}`` of the difference is the difference of the phasors, per axis.
    """
    dx = cmath.rect(pro_a.rho_x_m, pro_a.alpha_x_rad) - cmath.rect(pro_b.rho_x_m, pro_b.alpha_x_rad)
    dz = cmath.rect(pro_a.rho_z_m, pro_a.alpha_z_rad) - cmath.rect(pro_b.rho_z_m, pro_b.alpha_z_rad)
    return Pro(abs(dx), cmath.phase(dx), pro_a.rho_y_m - pro_b.rho_y_m, abs(dz), cmath.phase(dz))


def min_distance_between(pro_a: Pro, pro_b: Pro, n: float) -> tuple[float, float]:
    """Minimum distance between two spacecraft on PROs of the same chief, over one period.

    The relative motion ``a - b`` is itself a PRO (HCW linearity; the phasors subtract), so this
    is :func:`min_distance_to_origin` of the difference.

    Returns:
        ``(d_min_m, t_at_min_s)``, absolute time in ``[0, 2 pi / n)`` s.
    """
    return min_distance_to_origin(_difference(pro_a, pro_b), n)


def min_radial_normal_distance(pro: Pro) -> float:
    """Minimum over the orbit of ``sqrt(x^2 + z^2)`` (radial-normal separation), m.

    Closed form: ``x^2 + z^2 = (A + B)/2 - Re[(A e^{2i alpha_x} + B e^{2i alpha_z}) e^{2i n t}]/2``
    with ``A = rho_x^2``, ``B = rho_z^2``, so the minimum is
    ``((A + B) - |A e^{i Delta} + B|) / 2`` with ``Delta = 2 (alpha_x - alpha_z)``.  Since
    ``(A + B)^2 - |A e^{i Delta} + B|^2 = 4 A B sin^2(alpha_x - alpha_z)``, it is evaluated
    without cancellation as ``2 A B sin^2(alpha_x - alpha_z) / ((A + B) + |A e^{i Delta} + B|)``.

    Relation to the relative e/i vectors (D'Amico & Montenbruck, JGCD 29(3), 2006: ``x/a =
    -de cos(u - phi)``, ``z/a = di sin(u - theta)`` with ``u = n t``): matching with the PRO form
    gives ``a de = rho_x (cos phi, sin phi)``, ``phi = -alpha_x - pi/2`` and
    ``a di = rho_z (cos theta, sin theta)``, ``theta = -alpha_z``.  Parallel e/i vectors
    (``alpha_z = alpha_x + pi/2``) give ``min(rho_x, rho_z)``; perpendicular ones
    (``alpha_z = alpha_x``) give 0.
    """
    a2 = pro.rho_x_m**2
    b2 = pro.rho_z_m**2
    diff = pro.alpha_x_rad - pro.alpha_z_rad
    mag = abs(a2 * cmath.exp(2j * diff) + b2)
    denom = a2 + b2 + mag
    if denom == 0.0:
        return 0.0
    return math.sqrt(2.0 * a2 * b2 * math.sin(diff) ** 2 / denom)


def pro_ring(
    count: int, rho_x_m: float, rho_y_m: float, rho_z_m: float, phase0_rad: float = 0.0
) -> list[Pro]:
    """``count`` PROs of equal shape with phases ``alpha_x = alpha_z = phase0 + 2 pi i / count``.

    Note that ``alpha_x = alpha_z`` makes the radial and cross-track motions pass through zero
    together (perpendicular e/i vectors): the radial-normal separation is zero once per orbit and
    safety relies on the along-track offset at that instant (``rho_y +- 2 rho_x``).
    """
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count!r}")
    return [
        Pro(rho_x_m, phase0_rad + 2.0 * math.pi * i / count, rho_y_m, rho_z_m,
            phase0_rad + 2.0 * math.pi * i / count)
        for i in range(count)
    ]
