"""Onboard model of the target's LVLH frame in inertial space.

The flight software knows the target's orbit as a circular orbit (altitude, inclination, right
ascension of the ascending node, argument of latitude at t = 0) — the same convention as the
simulator's chief — and from it the rotation between LVLH and ECI at any mission time.  This is a
model: the truth orbit (two-body, optionally J2) departs from it, as an onboard ephemeris would.

LVLH axes: x radial (along the target position), z along the orbital angular momentum, y = z × x
(along-track).  The frame rotates at the mean motion n about its own z axis.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["lvlh_rate_lvlh", "lvlh_to_eci_quat", "orbit_plane_axes"]


def lvlh_to_eci_quat(
    t_s: float, n: float, inclination_rad: float, raan_rad: float = 0.0, arg_lat0_rad: float = 0.0
) -> np.ndarray:
    """Quaternion of R_eci_lvlh (the rotation taking LVLH vectors into ECI at mission time
    ``t_s``), scalar-last [x, y, z, w], shape (4,).

    R_eci_lvlh = R3(Ω) R1(i) R3(u) (3-1-3 Euler sequence: the columns of R3(Ω) R1(i) are the node
    line p, its in-plane normal q and the orbit normal; R3(u) turns p, q into the radial and
    along-track axes), so with the Hamilton product the quaternion is
    ``q_z(Ω) ⊗ q_x(i) ⊗ q_z(u)``, ``q_a(θ) = [sin(θ/2) â, cos(θ/2)]``, which multiplies out to

        [sin(i/2) cos((Ω − u)/2), sin(i/2) sin((Ω − u)/2),
         cos(i/2) sin((Ω + u)/2), cos(i/2) cos((Ω + u)/2)]

    (composition of the elementary-axis quaternions of an Euler sequence; Markley & Crassidis,
    *Fundamentals of Spacecraft Attitude Determination and Control*, 2014, Ch. 2).

    Sign: the largest-magnitude component is made positive (the first one on a tie), the sign
    scipy's ``Rotation.from_matrix`` (Shepperd's method) gives, so the quaternion is the one the
    former matrix-based construction returned.

    Args:
        t_s: mission time, s.
        n: mean motion, rad/s.
        inclination_rad: orbit inclination i, rad.
        raan_rad: right ascension of the ascending node Ω, rad.
        arg_lat0_rad: argument of latitude at t = 0, rad.

    Returns:
        The unit quaternion of R_eci_lvlh, (4,).
    """
    u = arg_lat0_rad + n * t_s
    half_i = 0.5 * inclination_rad
    diff, total = 0.5 * (raan_rad - u), 0.5 * (raan_rad + u)
    si, ci = math.sin(half_i), math.cos(half_i)
    q = [si * math.cos(diff), si * math.sin(diff), ci * math.sin(total), ci * math.cos(total)]
    largest = max(q, key=abs)
    return np.array(q) if largest >= 0.0 else -np.array(q)




def lvlh_rate_lvlh(n: float) -> np.ndarray:
    """Angular velocity of LVLH with respect to ECI, in LVLH axes: (0, 0, n) rad/s."""
    return np.array([0.0, 0.0, n])


def orbit_plane_axes(cos_raan: np.ndarray | float, sin_raan: np.ndarray | float,
                     cos_inc: float, sin_inc: float) -> tuple[np.ndarray, np.ndarray]:
    """The orbital plane's unit vectors in ECI: the node line p and its in-plane normal q (the
    first two columns of R3(Ω) R1(i)), from the cosines and sines of the node Ω and the
    inclination i.  A point of a circular orbit of radius r at argument of latitude u is
    r (cos u p + sin u q); its velocity is along -sin u p + cos u q.

    The node may be an array (a node that drifts with time): p and q then have shape (..., 3);
    for floats, shape (3,).  The caller takes the trigonometric functions, so each keeps its
    own arithmetic (the sim's chief state uses ``math``'s)."""
    co, so = np.asarray(cos_raan, dtype=float), np.asarray(sin_raan, dtype=float)
    p = np.stack([co, so, np.zeros_like(co)], axis=-1)
    q = np.stack([-so * cos_inc, co * cos_inc, np.full_like(co, sin_inc)], axis=-1)
    return p, q
