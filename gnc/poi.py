"""Prior model of the target: points of interest (POIs) sampled on its surface.

The target frame is centred on the target, which is the origin of the LVLH/HCW frame (x radial,
y along-track, z cross-track; metres).  The paper's higher-dimensional example (Sec. III.G) uses
POIs "uniformly distributed on the surface of a unit sphere"; :func:`sphere_pois` provides that
prior model for any radius and count, deterministically.

Pure functions only; no bus, no I/O, no randomness.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

__all__ = ["GOLDEN_ANGLE_RAD", "sphere_pois"]

#: Golden angle π(3 − √5) ≈ 2.39996 rad: the azimuth step of the Fibonacci lattice.
GOLDEN_ANGLE_RAD: float = math.pi * (3.0 - math.sqrt(5.0))


def sphere_pois(count: int,
                radius_m: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """``count`` points spread near-uniformly on a sphere of radius ``radius_m`` centred at the
    origin.

    Fibonacci (golden-angle) lattice (Swinbank & Purser, "Fibonacci grids: a novel approach to
    global modelling", QJRMS 132, 2006; González, "Measurement of areas on a sphere using
    Fibonacci and latitude-longitude lattices", Math. Geosci. 42, 2010): point ``i`` of ``count``
    has ``z_i = 1 − (2 i + 1)/count`` (equal-area bands: the area of a spherical zone is
    proportional to its height, Archimedes) and azimuth ``λ_i = i · π(3 − √5)``, so every point
    owns an equal area 4π r²/count and consecutive points are spread by the golden angle.

    Args:
        count: number of POIs M ≥ 1.
        radius_m: sphere radius in m (> 0, finite).

    Returns:
        ``(positions, normals)``: positions (M, 3) in m, all at distance ``radius_m`` from the
        origin; outward unit normals (M, 3) (the positions divided by the radius).

    Raises:
        ValueError: if ``count`` < 1 or ``radius_m`` is not a positive finite number.
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ValueError(f"count must be an integer >= 1, got {count!r}")
    if not (isinstance(radius_m, (int, float, np.floating)) and math.isfinite(radius_m)
            and radius_m > 0):
        raise ValueError(f"radius_m must be a positive finite number, got {radius_m!r}")
    i = np.arange(int(count), dtype=float)
    z = 1.0 - (2.0 * i + 1.0) / count
    rho = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    lam = i * GOLDEN_ANGLE_RAD
    normals = np.column_stack((rho * np.cos(lam), rho * np.sin(lam), z))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return float(radius_m) * normals, normals
