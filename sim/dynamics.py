"""Truth relative translational dynamics of N deputies about a chief in LEO.

This is the simulator's *truth* model, deliberately not the flight model
(HCW, :mod:`gnc.hcw`): gravity is full nonlinear two-body, optionally
with the J2 zonal harmonic, for the chief and every deputy, so the flight
software sees real model error (nonlinearity, orbit curvature, J2).

Conventions and units: SI throughout (m, s, rad, m/s, m/s^2).  ECI states
are ``[x, y, z, vx, vy, vz]``.  The LVLH (Hill) frame of the chief has

* x -- radial, along the chief position vector,
* z -- cross-track, along the chief orbital angular momentum h = r x v,
* y -- along-track, y = z x x.

Relative states are deputy minus chief.  A relative state "in LVLH" holds
the LVLH coordinates of the relative position and their time derivatives
as seen in the rotating frame; the frame rate used for the transport term
is ``omega = (|h| / |r|^2) z_hat``, which is exact for Keplerian motion.
(Under J2 the true LVLH frame also rotates about x at ``|r| a_h / |h|``,
~2e-6 rad/s in LEO, where a_h is the out-of-plane perturbing acceleration;
the conversion functions leave it out by definition, so
``eci_to_lvlh(lvlh_to_eci(.))`` is still an exact round trip.)

The Earth model is axisymmetric (J2 only), so Earth rotation, precession and
nutation are not needed: ECI z is taken as the Earth's spin axis.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from gnc.constants import J2_EARTH, MU_EARTH_M3_S2, R_EARTH_M
from gnc.frames import orbit_plane_axes
from sim import kernels

__all__ = [
    "RelativeTruth",
    "circular_chief_eci",
    "differential_gravity",
    "eci_to_lvlh",
    "energy_matched",
    "j2_accel_eci",
    "lvlh_basis",
    "lvlh_to_eci",
]

FloatArray = npt.NDArray[np.float64]


# --------------------------------------------------------------------------
# Orbits and frames
# --------------------------------------------------------------------------


def circular_chief_eci(
    altitude_m: float,
    inclination_rad: float = 0.9,
    raan_rad: float = 0.0,
    arg_lat_rad: float = 0.0,
    mu: float = MU_EARTH_M3_S2,
    r_earth: float = R_EARTH_M,
) -> FloatArray:
    """ECI state of a circular Keplerian orbit.

    Args:
        altitude_m: altitude above the equatorial radius, m.
        inclination_rad: inclination, rad.
        raan_rad: right ascension of the ascending node, rad.
        arg_lat_rad: argument of latitude (angle from the ascending node
            in the direction of motion), rad.
        mu: gravitational parameter, m^3/s^2.
        r_earth: equatorial radius, m.

    Returns:
        ``[x, y, z, vx, vy, vz]`` in m and m/s, shape (6,).
    """
    r = r_earth + altitude_m
    if r <= 0.0:
        raise ValueError(f"orbit radius must be positive, got {r!r} m")
    v = math.sqrt(mu / r)
    co, so = math.cos(raan_rad), math.sin(raan_rad)
    ci, si = math.cos(inclination_rad), math.sin(inclination_rad)
    cu, su = math.cos(arg_lat_rad), math.sin(arg_lat_rad)
    p, q = orbit_plane_axes(co, so, ci, si)
    pos = r * (cu * p + su * q)
    vel = v * (-su * p + cu * q)
    return np.concatenate([pos, vel])


def _basis_and_rate(chief_eci: FloatArray) -> tuple[FloatArray, float]:
    """LVLH basis (rows x, y, z in ECI) and the Keplerian frame rate |h|/r^2 (rad/s)."""
    rx, ry, rz, vx, vy, vz = chief_eci[:6].tolist()
    hx = ry * vz - rz * vy
    hy = rz * vx - rx * vz
    hz = rx * vy - ry * vx
    r2 = rx * rx + ry * ry + rz * rz
    rn = math.sqrt(r2)
    hn = math.sqrt(hx * hx + hy * hy + hz * hz)
    if rn == 0.0 or hn == 0.0:
        raise ValueError("chief state has zero radius or zero angular momentum")
    xr, yr, zr = rx / rn, ry / rn, rz / rn
    xh, yh, zh = hx / hn, hy / hn, hz / hn
    c = np.array(
        [
            [xr, yr, zr],
            [yh * zr - zh * yr, zh * xr - xh * zr, xh * yr - yh * xr],
            [xh, yh, zh],
        ]
    )
    return c, hn / r2


def lvlh_basis(chief_eci: npt.ArrayLike) -> FloatArray:
    """Rotation from ECI to the chief's LVLH frame.

    Args:
        chief_eci: chief ECI state, m and m/s, shape (6,).

    Returns:
        3x3 matrix C whose rows are the LVLH unit vectors (x radial,
        y along-track, z orbit normal) expressed in ECI, so that
        ``v_lvlh = C @ v_eci``.
    """
    c, _ = _basis_and_rate(np.asarray(chief_eci, dtype=float))
    return c


def lvlh_to_eci(chief_eci: npt.ArrayLike, rel_lvlh: npt.ArrayLike) -> FloatArray:
    """Relative state in the rotating LVLH frame -> relative state in ECI.

    ``dr = C^T rho`` and ``dv = C^T (rho_dot + omega x rho)`` with
    ``omega = (0, 0, |h|/|r|^2)`` in LVLH.

    Args:
        chief_eci: chief ECI state, shape (6,), m and m/s.
        rel_lvlh: relative states ``[x, y, z, vx, vy, vz]`` in LVLH (m, m/s),
            shape (..., 6), e.g. (N, 6).

    Returns:
        Deputy-minus-chief ECI states, same shape as ``rel_lvlh``.
    """
    c, w = _basis_and_rate(np.asarray(chief_eci, dtype=float))
    rel = np.asarray(rel_lvlh, dtype=float)
    rho = rel[..., 0:3]
    vel = rel[..., 3:6].copy()
    vel[..., 0] -= w * rho[..., 1]
    vel[..., 1] += w * rho[..., 0]
    out = np.empty(rel.shape)
    out[..., 0:3] = rho @ c
    out[..., 3:6] = vel @ c
    return out


def eci_to_lvlh(chief_eci: npt.ArrayLike, rel_eci: npt.ArrayLike) -> FloatArray:
    """Relative state in ECI -> relative state in the rotating LVLH frame.

    Inverse of :func:`lvlh_to_eci`: ``rho = C dr`` and
    ``rho_dot = C dv - omega x rho``.

    Args:
        chief_eci: chief ECI state, shape (6,), m and m/s.
        rel_eci: deputy-minus-chief ECI states, shape (..., 6), m and m/s.

    Returns:
        LVLH relative states, same shape as ``rel_eci``.
    """
    c, w = _basis_and_rate(np.asarray(chief_eci, dtype=float))
    rel = np.asarray(rel_eci, dtype=float)
    out = np.empty(rel.shape)
    out[..., 0:3] = rel[..., 0:3] @ c.T
    out[..., 3:6] = rel[..., 3:6] @ c.T
    out[..., 3] += w * out[..., 1]
    out[..., 4] -= w * out[..., 0]
    return out


def energy_matched(
    chief_eci: npt.ArrayLike, rel_eci: npt.ArrayLike, mu: float = MU_EARTH_M3_S2
) -> FloatArray:
    """Adjust deputy velocities so each deputy's two-body energy equals the chief's.

    Equal two-body specific energy means equal semi-major axis and hence equal
    Keplerian period, so the relative motion is periodic with no secular
    along-track drift (the nonlinear counterpart of the HCW condition
    ``vy0 = -2 n x0``, which only holds to first order in separation/radius).

    Choice made here: the deputy's position is kept and its *absolute* ECI
    velocity is scaled by a factor s (its direction kept), with
    ``|s v_d|^2 / 2 - mu / |r_d| = |v_c|^2 / 2 - mu / |r_c|``.  Scaling along
    the velocity direction changes energy most efficiently (the smallest
    velocity change), leaves the flight-path angle and orbit plane unchanged,
    and in LVLH acts almost purely along-track, so the PRO geometry is
    disturbed only at second order (|dv| ~ n rho^2 / r).

    The correction is evaluated without cancellation: with ``v_d = v_c + dv``
    and ``r_d = r_c + dr``,
    ``s^2 - 1 = [-(2 v_c.dv + |dv|^2) + 2 mu (1/|r_d| - 1/|r_c|)] / |v_d|^2``
    where ``1/|r_d| - 1/|r_c| = -(2 r_c.dr + |dr|^2) / (|r_c| |r_d| (|r_c| + |r_d|))``,
    and the new relative velocity is ``dv + (s - 1) v_d`` with
    ``s - 1 = (s^2 - 1) / (s + 1)``.

    Only two-body energy is matched; with J2 the mean semi-major axes still
    differ slightly.  Do not apply to deputies meant to drift.

    Args:
        chief_eci: chief ECI state, shape (6,), m and m/s.
        rel_eci: deputy-minus-chief ECI states, shape (N, 6) (or (6,)).
        mu: gravitational parameter, m^3/s^2.

    Returns:
        New relative ECI states, same shape; positions unchanged.

    Raises:
        ValueError: if a deputy cannot reach the chief's energy at its
            position (would need an imaginary speed).
    """
    chief = np.asarray(chief_eci, dtype=float)
    rel = np.array(rel_eci, dtype=float)
    rc = chief[0:3]
    vc = chief[3:6]
    dr = rel[..., 0:3]
    dv = rel[..., 3:6]
    rcn = math.sqrt(float(rc @ rc))
    rd = rc + dr
    vd = vc + dv
    rdn = np.sqrt(np.sum(rd * rd, axis=-1))
    vd2 = np.sum(vd * vd, axis=-1)
    d_inv_r = -(2.0 * (dr @ rc) + np.sum(dr * dr, axis=-1)) / (rcn * rdn * (rcn + rdn))
    num = -(2.0 * (dv @ vc) + np.sum(dv * dv, axis=-1)) + 2.0 * mu * d_inv_r
    s2m1 = num / vd2
    if np.any(s2m1 <= -1.0):
        raise ValueError("a deputy cannot reach the chief's orbital energy by a speed change")
    sm1 = s2m1 / (1.0 + np.sqrt(1.0 + s2m1))
    rel[..., 3:6] = dv + sm1[..., None] * vd
    return rel


# --------------------------------------------------------------------------
# Accelerations
# --------------------------------------------------------------------------


def j2_accel_eci(
    r_eci: npt.ArrayLike,
    mu: float = MU_EARTH_M3_S2,
    r_earth: float = R_EARTH_M,
    j2: float = J2_EARTH,
) -> FloatArray:
    """J2 perturbing acceleration (gradient of the J2 term of the geopotential).

    ``a = -(3/2) J2 mu R^2 / r^5 * [x (1 - 5 z^2/r^2), y (1 - 5 z^2/r^2), z (3 - 5 z^2/r^2)]``
    (Vallado Eq. 8-30 form).  At the equator (z = 0) it is radial, inward, of
    magnitude ``(3/2) J2 mu R^2 / r^4``.

    Args:
        r_eci: ECI positions, m, shape (..., 3).
        mu: gravitational parameter, m^3/s^2.
        r_earth: equatorial radius, m.
        j2: J2 coefficient.

    Returns:
        Accelerations, m/s^2, shape (..., 3).
    """
    r = np.asarray(r_eci, dtype=float)
    r2 = np.sum(r * r, axis=-1)
    k = (-1.5 * j2 * mu * r_earth * r_earth) / (r2 * r2 * np.sqrt(r2))
    g = 1.0 - 5.0 * r[..., 2] * r[..., 2] / r2
    out: FloatArray = r * (k * g)[..., None]
    out[..., 2] += 2.0 * k * r[..., 2]
    return out


def differential_gravity(
    r_chief: npt.ArrayLike, dr: npt.ArrayLike, mu: float = MU_EARTH_M3_S2
) -> FloatArray:
    """Two-body gravity of the deputies minus that of the chief, cancellation-free.

    ``g(r_c + dr) - g(r_c) = -(mu / r_c^3) [dr + f(q) (r_c + dr)]`` where,
    with ``r_d = r_c + dr``, ``q = dr . (dr - 2 r_d) / r_d^2`` so that
    ``r_c^2 = r_d^2 (1 + q)``, and
    ``f(q) = (1 + q)^{3/2} - 1 = q (3 + 3 q + q^2) / (1 + (1 + q)^{3/2})``
    (Battin, *An Introduction to the Mathematics and Methods of
    Astrodynamics*, Sec. 8.4).  Every small quantity (q, f, dr) is formed from
    small quantities only, so the relative error stays at round-off level
    however small dr is, instead of ~eps * |g| / |dg| ~ eps * r / |dr| for a
    plain difference of two absolute accelerations.

    Args:
        r_chief: chief ECI position, m, shape (3,).
        dr: deputy-minus-chief ECI positions, m, shape (N, 3).
        mu: gravitational parameter, m^3/s^2.

    Returns:
        Differential accelerations, m/s^2, shape (N, 3).
    """
    rc = np.asarray(r_chief, dtype=float)
    d = np.asarray(dr, dtype=float)
    if d.ndim != 2 or d.shape[1] != 3:
        raise ValueError(f"dr must have shape (N, 3), got {d.shape}")
    rc2 = float(rc @ rc)
    return _dgrav(rc, rc2, d, mu / (rc2 * math.sqrt(rc2)))[0]


def _dgrav(
    rc: FloatArray, rc2: float, dr: FloatArray, mu_over_rc3: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Battin differential gravity; also returns r_d (N, 3) and |r_d|^2 (N,) for reuse.

    ``p = |r_d|^2 - |r_c|^2 = dr.(dr + 2 r_c)`` is formed from small terms, then
    ``q = -p / |r_d|^2`` and ``1 + q = |r_c|^2 / |r_d|^2``.
    """
    p = np.einsum("ij,ij->i", dr, dr) + 2.0 * (dr @ rc)
    rd2 = p + rc2
    q = -p / rd2
    opq = rc2 / rd2
    f = q * (3.0 + q * (3.0 + q)) / (1.0 + opq * np.sqrt(opq))
    rd = dr + rc
    acc = rd * f[:, None]
    acc += dr
    acc *= -mu_over_rc3
    return acc, rd, rd2


# --------------------------------------------------------------------------
# Truth propagator
# --------------------------------------------------------------------------


class RelativeTruth:
    """Nonlinear truth propagation of a chief and N deputies.

    State: the chief's absolute ECI state (6,) and the deputies' *relative*
    ECI states (deputy minus chief, (N, 6)), integrated together.  The relative
    state is integrated directly, not as a difference of two absolute
    states, so separations of metres keep full double precision (an absolute
    ECI coordinate of ~7e6 m only resolves ~1e-9 m, and differencing two
    absolute accelerations would lose ~log10(r/|dr|) digits).  The
    differential two-body gravity uses Battin's f(q) formulation
    (:func:`differential_gravity`).  The differential J2 acceleration is a
    plain difference of two J2 accelerations: |a_J2| ~ 1e-2 m/s^2, so its
    absolute round-off (~1e-18 m/s^2) is negligible.

    Integration: classical fixed-step RK4 over the stacked (N+1, 6) array,
    vectorised over the deputies.  An optional per-deputy acceleration (thrust
    or disturbance) given in the chief's LVLH frame is held constant over
    each ``step`` call and rotated into ECI with the LVLH basis of the chief
    state at every RK stage.  The chief has no control input.

    Attributes:
        t_s: current simulation time, s.
    """

    def __init__(
        self,
        chief_eci: npt.ArrayLike,
        rel_lvlh: npt.ArrayLike,
        j2: bool = False,
        energy_match: bool = True,
        t0_s: float = 0.0,
        *,
        compiled: bool = True,
        mu: float = MU_EARTH_M3_S2,
        r_earth: float = R_EARTH_M,
        j2_coeff: float = J2_EARTH,
    ) -> None:
        """Initialise from the chief ECI state and deputies' LVLH relative states.

        Args:
            chief_eci: chief ECI state, shape (6,), m and m/s.
            rel_lvlh: deputy relative states in LVLH, shape (N, 6), m and m/s
                (e.g. from :func:`gnc.hcw.pro_state`).
            j2: include the J2 perturbation on chief and deputies.
            energy_match: apply :func:`energy_matched` to the initial
                deputies so that their two-body semi-major axes equal the
                chief's (no secular drift of an HCW-designed PRO).
            t0_s: initial time, s.
            compiled: integrate with the compiled kernel (:func:`sim.kernels.relative_rk4`);
                False runs the numpy reference below.
            mu: gravitational parameter, m^3/s^2.
            r_earth: equatorial radius for J2, m.
            j2_coeff: J2 coefficient.
        """
        chief = np.array(chief_eci, dtype=float)
        if chief.shape != (6,):
            raise ValueError(f"chief_eci must have shape (6,), got {chief.shape}")
        rel = np.array(rel_lvlh, dtype=float)
        if rel.ndim != 2 or rel.shape[1] != 6:
            raise ValueError(f"rel_lvlh must have shape (N, 6), got {rel.shape}")
        rel_eci = lvlh_to_eci(chief, rel)
        if energy_match:
            rel_eci = energy_matched(chief, rel_eci, mu=mu)
        self._y: FloatArray = np.empty((rel.shape[0] + 1, 6))
        self._y[0] = chief
        self._y[1:] = rel_eci
        self._mu = float(mu)
        self._j2 = bool(j2)
        self._j2_k = -1.5 * float(j2_coeff) * float(mu) * float(r_earth) ** 2
        self.t_s: float = float(t0_s)
        self.compiled = compiled

    # ----- state access ---------------------------------------------------

    @property
    def n_deputies(self) -> int:
        """Number of deputies N."""
        return int(self._y.shape[0]) - 1

    @property
    def j2(self) -> bool:
        """Whether the J2 perturbation is modelled."""
        return self._j2

    @property
    def chief_eci(self) -> FloatArray:
        """Chief ECI state (6,), m and m/s (a copy)."""
        out: FloatArray = self._y[0].copy()
        return out

    @property
    def rel_eci(self) -> FloatArray:
        """Deputy-minus-chief ECI states (N, 6), m and m/s (a copy)."""
        out: FloatArray = self._y[1:].copy()
        return out

    def rel_lvlh(self) -> FloatArray:
        """Deputy relative states in the chief's LVLH frame (N, 6), m and m/s."""
        return eci_to_lvlh(self._y[0], self._y[1:])

    def positions_lvlh(self) -> FloatArray:
        """Deputy relative positions in the chief's LVLH frame (N, 3), m."""
        c, _ = _basis_and_rate(self._y[0])
        return self._y[1:, 0:3] @ c.T

    def disturb(self, delta_lvlh: npt.ArrayLike) -> None:
        """Add ``delta_lvlh`` (N, 6: m, m/s, in the chief's LVLH frame) to the deputies'
        relative states at once (a state disturbance: ``faults/hardware.py``)."""
        rel = self.rel_lvlh() + np.asarray(delta_lvlh, dtype=float)
        self._y[1:] = lvlh_to_eci(self._y[0], rel)

    # ----- dynamics ---------------------------------------------------------

    def _deriv(self, y: FloatArray, a_lvlh: FloatArray | None) -> FloatArray:
        """Time derivative of the stacked state: row 0 chief absolute, rows 1.. relative."""
        out = np.empty_like(y)
        out[:, 0:3] = y[:, 3:6]
        rc = y[0, 0:3]
        rcx, rcy, rcz = rc.tolist()
        rc2 = rcx * rcx + rcy * rcy + rcz * rcz
        k = self._mu / (rc2 * math.sqrt(rc2))
        acc, rd, rd2 = _dgrav(rc, rc2, y[1:, 0:3], k)
        acx, acy, acz = -k * rcx, -k * rcy, -k * rcz
        if self._j2:
            # Chief with scalars, deputies vectorised; differential = difference.
            kc = self._j2_k / (rc2 * rc2 * math.sqrt(rc2))
            gc = kc * (1.0 - 5.0 * rcz * rcz / rc2)
            ajc = np.array([gc * rcx, gc * rcy, (gc + 2.0 * kc) * rcz])
            kd = self._j2_k / (rd2 * rd2 * np.sqrt(rd2))
            zd = rd[:, 2]
            gd = kd * (1.0 - 5.0 * zd * zd / rd2)
            aj = rd * gd[:, None]
            aj[:, 2] += 2.0 * kd * zd
            aj -= ajc
            acc += aj
            acx += ajc[0]
            acy += ajc[1]
            acz += ajc[2]
        if a_lvlh is not None:
            c, _ = _basis_and_rate(y[0])
            acc += a_lvlh @ c
        out[1:, 3:6] = acc
        out[0, 3:6] = (acx, acy, acz)
        return out

    def step(
        self,
        dt_s: float,
        accel_lvlh: npt.ArrayLike | None = None,
        substeps: int = 1,
    ) -> None:
        """Advance all spacecraft by ``dt_s`` with classical RK4.

        Args:
            dt_s: time to advance, s (the RK4 step is ``dt_s / substeps``).
            accel_lvlh: optional per-deputy acceleration in the chief's LVLH
                frame, m/s^2, shape (N, 3) (anything broadcastable to it),
                held constant over the whole call and re-rotated into ECI at
                every RK stage.
            substeps: number of RK4 steps to take within ``dt_s`` (>= 1).
        """
        if substeps < 1:
            raise ValueError(f"substeps must be >= 1, got {substeps!r}")
        a: FloatArray | None = None
        if accel_lvlh is not None:
            a = np.broadcast_to(np.asarray(accel_lvlh, dtype=float), (self.n_deputies, 3))
        if self.compiled:
            accel = np.zeros((self.n_deputies, 3)) if a is None else np.ascontiguousarray(a)
            self._y = kernels.relative_rk4(self._y, accel, a is not None, self._mu, self._j2,
                                           self._j2_k, float(dt_s), int(substeps))
            self.t_s += float(dt_s)
            return
        h = float(dt_s) / substeps
        y = self._y
        f = self._deriv
        for _ in range(substeps):
            k1 = f(y, a)
            k2 = f(y + (0.5 * h) * k1, a)
            k3 = f(y + (0.5 * h) * k2, a)
            k4 = f(y + h * k3, a)
            k2 += k3
            k2 *= 2.0
            k2 += k1
            k2 += k4
            y = y + (h / 6.0) * k2
        self._y = y
        self.t_s += float(dt_s)
