"""Physical constants for Earth-orbit work, in SI units.

Values follow the EGM-96 / WGS-84 set used by Vallado, *Fundamentals of
Astrodynamics and Applications* (4th ed.), Table D-1, except that the
gravitational parameter carries the IERS digits (398600.4418 km^3/s^2).
"""

from __future__ import annotations

from typing import Final

MU_EARTH_M3_S2: Final[float] = 398600.4418e9
"""Earth gravitational parameter GM, m^3/s^2."""

R_EARTH_M: Final[float] = 6378136.3
"""Earth equatorial radius, m."""

J2_EARTH: Final[float] = 1.08262668e-3
"""Earth second zonal harmonic J2 (unnormalized), dimensionless."""

__all__ = ["J2_EARTH", "MU_EARTH_M3_S2", "R_EARTH_M"]
