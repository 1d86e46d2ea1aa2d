"""Compiled kernel of the per-observation precision (Eq. 5, 14): the sim's cameras and the ground's
nominal twin.

The same test and formula as :func:`gnc.infocost.precision` -- visible ⇔ inside the cone
(b·(s − p) > 0 and (b·(s − p))² ≥ cos²α d²), 0 < d² ≤ R², front-facing (n·(p − s) > 0) -- with
d² = |p|² + |s|² − 2 p·s as there, in one compiled pass over cameras × POIs (numba, cached on
disk) instead of numpy's blocked temporaries: the FDIR's twin, hardware threshold and Eq.
11-12 sampling image thousands of poses a window, and there numpy's arithmetic on
temporaries, not the work, set the cost (≈60 ns per camera-POI pair; ≈1 ns compiled, the POIs
read as contiguous columns (``gnc.infocost.PoiSet``) on SIMD lanes).

The numpy version stays the tested reference (``tests/gnc/test_infocost_kernels.py``): values
equal to rounding, a visibility decided differently only on a pair within rounding of the cone,
range or horizon boundary.  The sim's cameras use it too (``sim.camera.TruthCameras``, whose
``compiled=False`` runs the numpy version).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

from gnc.infocost import TINY, Camera, PoiSet, checked_cameras

FloatArray = npt.NDArray[np.float64]


@njit(cache=True, error_model="numpy")
def _fill(p: FloatArray, b: FloatArray, sx: FloatArray, sy: FloatArray, sz: FloatArray,
          ss: FloatArray, nx: FloatArray, ny: FloatArray, nz: FloatArray, ns: FloatArray,
          facing: bool, cos2: float, r2: float, inv_k: float, out: FloatArray) -> None:
    # Branch-free over the POIs, each (M,) array contiguous: the compiler runs the inner loop
    # on SIMD lanes (≈1 ns a pair where a test-and-continue loop took 4).  The numpy error
    # model: a division never raises (d² ≥ TINY anyway), so no check stops the vectoriser.
    for i in range(p.shape[0]):
        px, py, pz = p[i, 0], p[i, 1], p[i, 2]
        bx, by, bz = b[i, 0], b[i, 1], b[i, 2]
        pp = px * px + py * py + pz * pz
        bp = bx * px + by * py + bz * pz
        row = out[i]
        for j in range(sx.shape[0]):
            front = True
            if facing:
                front = (px * nx[j] + py * ny[j] + pz * nz[j]) - ns[j] > 0.0
            proj = (bx * sx[j] + by * sy[j] + bz * sz[j]) - bp
            d2 = max(pp + ss[j] - 2.0 * (px * sx[j] + py * sy[j] + pz * sz[j]), 0.0)
            seen = front and proj > 0.0 and proj * proj >= cos2 * d2 and 0.0 < d2 <= r2
            row[j] = inv_k / max(d2, TINY) if seen else 0.0


def precision(cam_pos: npt.ArrayLike, boresight: npt.ArrayLike, poi_pos: npt.ArrayLike,
              poi_normal: npt.ArrayLike | None, camera: Camera) -> FloatArray:
    """σ⁻¹ (N, M) = 1/(k d²) where visible, else 0: :func:`gnc.infocost.precision`
    compiled (same arguments, same validation and errors)."""
    p, b = checked_cameras(cam_pos, boresight, camera)
    return _precision(p, b, PoiSet(poi_pos, poi_normal), camera)


def precision_on(cam_pos: npt.ArrayLike, boresight: npt.ArrayLike, pois: PoiSet,
                 camera: Camera) -> FloatArray:
    """:func:`precision` of POIs validated once (``pois``): only the cameras are checked."""
    p, b = checked_cameras(cam_pos, boresight, camera)
    return _precision(p, b, pois, camera)


def _precision(p: FloatArray, b: FloatArray, pois: PoiSet, camera: Camera) -> FloatArray:
    """σ⁻¹ (N, M) of validated cameras p (N, 3), m, and unit boresights b (N, 3)."""
    out = np.empty((p.shape[0], pois.pos.shape[0]))
    _fill(p, b, *pois.columns, pois.normal is not None,
          float(np.cos(camera.half_angle_rad)) ** 2, camera.max_range_m ** 2, 1.0 / camera.k,
          out)
    return out
