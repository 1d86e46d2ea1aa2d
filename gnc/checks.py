"""Input checks shared by the pure algorithms: bad input is a clear ValueError, never a NaN
that travels on."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["finite_array"]


def finite_array(name: str, value: npt.ArrayLike,
                 shape: tuple[int, ...]) -> npt.NDArray[np.float64]:
    """``value`` as a float array of exactly ``shape`` with only finite entries.

    Raises:
        ValueError: naming ``name``, if the value is not numeric, has another shape, or holds
            NaN or infinity.
    """
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric with shape {shape}") from exc
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name} contains NaN or infinite values")
    return a
