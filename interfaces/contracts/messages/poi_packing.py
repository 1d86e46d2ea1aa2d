"""The wire form of an image's POI set and precisions: the decimal digits a measured precision
carries (``quantise``).

A measured precision σ⁻¹ (Eq. 5) carries ``PRECISION_DIGITS`` significant digits: far below
the camera's noise (5% by default), and the images' JSON on the bus and in the archive is
half the size it is with 17-digit floats.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

PRECISION_DIGITS = 6
"""Significant digits of a measured σ⁻¹ (the camera noise is 5% by default)."""


def quantise(values: FloatArray, digits: int = PRECISION_DIGITS) -> FloatArray:
    """Round positive ``values`` to ``digits`` significant digits, as the nearest doubles of the
    rounded decimals (n / 10^k with an exact power of ten), so their shortest decimal form has
    at most ``digits`` digits.  Zeros stay zero."""
    out = np.zeros_like(values)
    pos = values > 0.0
    k = digits - 1 - np.floor(np.log10(values[pos]))
    scale = 10.0 ** np.abs(k)
    v = values[pos]
    out[pos] = np.where(k >= 0, np.round(v * scale) / scale, np.round(v / scale) * scale)
    return out
