"""The least squares of the camera trilateration (``ground.fdir.identify.locate_camera``) by its
normal equations, accumulated in one compiled pass over an image's POIs.

The fit is k σ⁻¹_j [1, s_j] · θ ≈ 1 over the n POIs an image saw (θ = [a, g], 4 unknowns).
With A the (n, 4) matrix of rows k σ⁻¹_j [1, s_j], the solution of AᵀA θ = Aᵀ1 is the
least-squares one.  AᵀA is 4 × 4: forming it costs a few flops per POI, where a
factorisation of A (``numpy.linalg.lstsq``'s SVD) made the ground FDIR's largest single cost
(0.18 ms an image of 2,000 POIs, 30 images a window).  The price is the condition number,
squared: κ(A) is about 10 for a camera 20-30 m from the default target (so κ(AᵀA) ≈ 100 and
the solution keeps 14 digits), and a fit with κ(A) above ``MAX_CONDITION`` (POIs close to a
plane, or a tiny cap of them) is refused, where the SVD's rank test refused only an exactly
degenerate one (κ beyond 10¹³ at 2,000 POIs).

The numpy version (:func:`normal_equations_reference`) is the tested reference of the compiled
one (``tests/ground/fdir/test_trilateration.py``).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

FloatArray = npt.NDArray[np.float64]

MAX_CONDITION = 1e6
"""The largest condition number κ(A) of a fit solved (the normal equations keep about
16 − 2 log₁₀ κ digits: 4 here, far more than an image's noise)."""


def normal_equations_reference(s: FloatArray, seen: npt.NDArray[np.int64], kp: FloatArray
                               ) -> tuple[FloatArray, FloatArray, int]:
    """AᵀA (4, 4), Aᵀ1 (4,) and the row count of the rows kp_j [1, s_j] over the POIs ``seen``
    (indices into ``s`` (M, 3), m) whose ``kp`` (one per seen POI) is positive: numpy, the
    reference of :func:`normal_equations`."""
    good = kp > 0.0
    a = kp[good, None] * np.c_[np.ones(int(good.sum())), s[seen[good]]]
    return a.T @ a, a.sum(axis=0), int(good.sum())


@njit(cache=True)
def normal_equations(s: FloatArray, seen: npt.NDArray[np.int64], kp: FloatArray
                     ) -> tuple[FloatArray, FloatArray, int]:
    """:func:`normal_equations_reference` in one compiled pass (no gathered copy)."""
    ata = np.zeros((4, 4))
    atb = np.zeros(4)
    row = np.empty(4)
    rows = 0
    for j in range(seen.shape[0]):
        w = kp[j]
        if not w > 0.0:
            continue
        rows += 1
        i = seen[j]
        row[0] = w
        row[1] = w * s[i, 0]
        row[2] = w * s[i, 1]
        row[3] = w * s[i, 2]
        for p in range(4):
            atb[p] += row[p]
            for q in range(p, 4):
                ata[p, q] += row[p] * row[q]
    for p in range(4):
        for q in range(p):
            ata[p, q] = ata[q, p]
    return ata, atb, rows


@njit(cache=True)
def normal_equations_each(s: FloatArray, seen: npt.NDArray[np.int64], kp: FloatArray,
                          starts: npt.NDArray[np.int64]
                          ) -> tuple[FloatArray, FloatArray, npt.NDArray[np.int64]]:
    """:func:`normal_equations` of several images at once, their seen POIs and ``kp``
    concatenated, image i's from ``starts[i]`` to ``starts[i + 1]``: AᵀA (n, 4, 4), Aᵀ1
    (n, 4), rows (n,), each summed as the image alone."""
    n = starts.shape[0] - 1
    ata = np.empty((n, 4, 4))
    atb = np.empty((n, 4))
    rows = np.empty(n, dtype=np.int64)
    for i in range(n):
        a, b = starts[i], starts[i + 1]
        ata[i], atb[i], rows[i] = normal_equations(s, seen[a:b], kp[a:b])
    return ata, atb, rows


def least_squares(s: FloatArray, seen: npt.NDArray[np.int64], kp: FloatArray, min_rows: int
                  ) -> FloatArray | None:
    """θ (4,) minimising |A θ − 1| for the rows kp_j [1, s_j] of the POIs ``seen`` (indices
    into ``s`` (M, 3), m) with a positive ``kp`` (one per seen POI); None with fewer than
    ``min_rows`` such rows, or when κ(A) exceeds ``MAX_CONDITION``."""
    starts = np.array([0, len(seen)], dtype=np.int64)
    return least_squares_each(s, seen, kp, starts, min_rows)[0]


def _check(s: FloatArray, seen: npt.NDArray[np.int64], kp: FloatArray,
           starts: npt.NDArray[np.int64]) -> None:
    """Refuse what the compiled pass, which checks no index, cannot read safely: positions not
    (M, 3) float, indices not integers in [0, M), a ``kp`` per index missing, image bounds
    ``starts`` not from 0 to the end, ascending."""
    if not (s.ndim == 2 and s.shape[1] == 3 and s.dtype == np.float64):
        raise ValueError(f"POI positions must be an (M, 3) float array, got {s.shape} {s.dtype}")
    if not (seen.ndim == 1 and np.issubdtype(seen.dtype, np.integer)
            and kp.ndim == 1 and len(kp) == len(seen)):
        raise ValueError(f"{kp.shape} precisions for {seen.shape} {seen.dtype} POI indices")
    if len(seen) and not 0 <= seen.min() <= seen.max() < len(s):
        raise ValueError(f"POI indices beyond the target's {len(s)} POIs")
    if not (starts.ndim == 1 and len(starts) >= 1 and starts[0] == 0
            and starts[-1] == len(seen) and np.all(np.diff(starts) >= 0)):
        raise ValueError(f"image bounds must run from 0 to {len(seen)}, ascending")


def least_squares_each(s: FloatArray, seen: npt.NDArray[np.int64], kp: FloatArray,
                       starts: npt.NDArray[np.int64], min_rows: int) -> list[FloatArray | None]:
    """:func:`least_squares` of each image, the images' ``seen`` and ``kp`` concatenated
    (image i's from ``starts[i]`` to ``starts[i + 1]``): one compiled pass and one batched
    solve, the same values as image by image."""
    _check(s, seen, kp, starts)
    ata, atb, rows = normal_equations_each(s, seen, kp, starts)
    ok = rows >= min_rows
    out: list[FloatArray | None] = [None] * len(rows)
    if not ok.any():
        return out
    eig = np.linalg.eigvalsh(ata[ok])  # ascending; κ(A)² = λ_max / λ_min
    ok[ok] = eig[:, 0] > eig[:, -1] / MAX_CONDITION**2
    if ok.any():
        coef = np.linalg.solve(ata[ok], atb[ok][:, :, None])[:, :, 0]
        for i, c in zip(np.flatnonzero(ok), coef, strict=True):
            out[i] = c
    return out
