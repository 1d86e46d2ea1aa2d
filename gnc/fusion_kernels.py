"""Compiled fusion of an image's precisions into accumulated precision (numba, cached on disk):
the N² fan-out of a constellation, where every observer fuses every image it receives
(``gnc.poi_map.PoiMap.add``, Eq. 7) and the ground rebuilds what each fused
(``ground.fdir.fused_views.FusedViews.add``).

Each kernel does in one pass over the image's POIs what the numpy version does in several (the
checks, then the indexed add), with the same additions in the same order, so the sums are the
same bits.  The numpy versions stay the tested reference (``tests/gnc/test_fusion_kernels.py``).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from numba import njit

__all__ = ["ADDED", "BAD_INDEX", "NOT_FINITE", "add_checked", "add_to_rows"]

ADDED, NOT_FINITE, BAD_INDEX = 0, 1, 2
"""What :func:`add_checked` did: added; nothing, a precision is not finite; nothing, an index
is out of range or a precision negative."""


@njit(cache=True)
def add_checked(row: npt.NDArray[np.float64], idx: npt.NDArray[np.int64],
                prec: npt.NDArray[np.float64]) -> int:
    """``row[idx[k]] += prec[k]`` for every k in order (a repeated index adds up, as
    ``np.add.at``), once every precision is finite (else :data:`NOT_FINITE`), every index
    within ``row`` and every precision ≥ 0 (else :data:`BAD_INDEX`); nothing is added unless
    all are.  ``idx`` and ``prec`` have the same length (the caller checks)."""
    for k in range(prec.shape[0]):
        if not math.isfinite(prec[k]):
            return NOT_FINITE
    m = row.shape[0]
    for k in range(idx.shape[0]):
        if idx[k] < 0 or idx[k] >= m or prec[k] < 0.0:
            return BAD_INDEX
    for k in range(idx.shape[0]):
        row[idx[k]] += prec[k]
    return ADDED


@njit(cache=True)
def add_to_rows(table: npt.NDArray[np.float64], rows: npt.NDArray[np.int64], source: int,
                idx: npt.NDArray[np.int64], prec: npt.NDArray[np.float64]) -> bool:
    """``table[r, source, idx] += prec`` for every r of ``rows``: an image of observer
    ``source`` joining the views of the receivers ``rows`` (indices into ``table``'s first
    axis).  Only for strictly increasing POIs ``idx`` (an image's) within ``table``'s last
    axis and ``prec`` of the same length: False, with nothing added, otherwise (numpy's indexed
    ``+=`` then decides what a repeated index does)."""
    m = table.shape[2]
    if prec.shape[0] != idx.shape[0]:
        return False
    for k in range(idx.shape[0]):
        if idx[k] < 0 or idx[k] >= m or (k > 0 and idx[k] <= idx[k - 1]):
            return False
    for r in rows:
        view = table[r, source]
        for k in range(idx.shape[0]):
            view[idx[k]] += prec[k]
    return True
