"""Linear interpolation of a reported time series at a few times, each value farther than a
gap from every sample marked unknown (NaN): what the ground's FDIR asks of an observer's
attitude and nav reports at each image it scores (``ground.fdir.observer.TimeSeries``).

:func:`columns_at` is the compiled kernel, one call for every column and time, with
``numpy.interp``'s arithmetic and ends (the value held beyond the first and last sample,
a sample's own value at its time, numpy's fallbacks for a non-finite slope), so its bits
are those of :func:`columns_at_reference`, the numpy version it replaces (one
``numpy.interp`` per column: on one or two times their calls, not arithmetic, set the cost),
which stays the tested reference (``tests/gnc/test_interpolate.py``).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

FloatArray = npt.NDArray[np.float64]


def columns_at_reference(times: FloatArray, t: FloatArray, columns: FloatArray,
                         max_gap_s: float) -> FloatArray:
    """Each column of ``columns`` (d, N), sampled at ``t`` (N,, increasing, s), interpolated
    at ``times`` (K,): (K, d), NaN at a time farther than ``max_gap_s`` from every sample."""
    j = np.searchsorted(t, times)  # in [0, N]
    before = np.abs(times - t[np.maximum(j - 1, 0)])
    after = np.abs(t[np.minimum(j, len(t) - 1)] - times)
    out = np.empty((len(times), len(columns)))
    for c, column in enumerate(columns):
        out[:, c] = np.interp(times, t, column)
    out[np.minimum(before, after) > max_gap_s] = np.nan
    return out


@njit(cache=True, error_model="numpy")  # x/0: inf or NaN, as numpy
def columns_at(times: FloatArray, t: FloatArray, columns: FloatArray,
               max_gap_s: float) -> FloatArray:
    """:func:`columns_at_reference`, compiled (the same bits)."""
    n, d = len(t), columns.shape[0]
    out = np.empty((len(times), d))
    for i in range(len(times)):
        x = times[i]
        j = np.searchsorted(t, x)  # the gap: as the reference, from the left insertion point
        before = abs(x - t[max(j - 1, 0)])
        after = abs(t[min(j, n - 1)] - x)
        if min(before, after) > max_gap_s:
            out[i, :] = np.nan
            continue
        k = np.searchsorted(t, x, side="right") - 1  # numpy.interp's interval: t[k] <= x
        for c in range(d):
            out[i, c] = _interp_one(x, t, columns[c], k)
    return out


@njit(cache=True, error_model="numpy")  # x/0: inf or NaN, as numpy
def _interp_one(x: float, t: FloatArray, y: FloatArray, k: int) -> float:
    """``numpy.interp(x, t, y)`` with ``k`` the last index whose ``t`` is at or before ``x``
    (−1: none), in numpy's arithmetic."""
    n = len(t)
    if np.isnan(x):
        return x
    if n == 1 or k < 0:  # one sample, or before the first: the first value
        return y[0]
    if k >= n - 1 or t[k] == x:
        return y[min(k, n - 1)]
    slope = (y[k + 1] - y[k]) / (t[k + 1] - t[k])
    value = slope * (x - t[k]) + y[k]
    if np.isnan(value):  # numpy's fallbacks: from the other end, then a flat interval
        value = slope * (x - t[k + 1]) + y[k + 1]
        if np.isnan(value) and y[k] == y[k + 1]:
            value = y[k]
    return value
