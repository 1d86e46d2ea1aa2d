"""The information-cost fault metric (paper Eq. 9-10), its direction (Table 3) and the global
check (Eq. 6).  Pure functions of the information-cost changes over one FDI window.

Notation: over the window [t − Δt, t] agent i's contribution changed by
``ΔH_i = H_i(t) − H_i(t − Δt)`` (from its telemetry) while the nominal twin predicted
``ΔH_i^pred = H_i^pred(t) − H_i(t − Δt)``; ``x = ΔH_i / ΔH_i^pred``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

import numpy as np

Direction = Literal["improved", "degraded"]

NON_DEGENERATE_REL = 1e-9
"""|ΔH_i^pred| below this fraction of |H_i(t − Δt)| (or exactly zero) is degenerate: the metric
is undefined (Theorem 1, assumption 1), not zero."""


def _defined(dh_pred: float, h_prev: float) -> bool:
    return math.isfinite(dh_pred) and abs(dh_pred) > NON_DEGENERATE_REL * max(abs(h_prev), 1e-300)


def ratio(dh: float, dh_pred: float, h_prev: float = 0.0) -> float | None:
    """``x = ΔH_i / ΔH_i^pred`` (Eq. 19's r_i), or None when the prediction is degenerate or an
    input is not finite."""
    if not (math.isfinite(dh) and _defined(dh_pred, h_prev)):
        return None
    return dh / dh_pred


def metric(dh: float, dh_pred: float, h_prev: float = 0.0) -> float | None:
    """``H_m,i = |1 − ΔH_i / ΔH_i^pred|`` (Eq. 9); None when undefined (see :func:`ratio`).

    Args:
        dh: actual change ΔH_i over the window.
        dh_pred: predicted nominal change ΔH_i^pred over the same window.
        h_prev: H_i(t − Δt), the scale for the degeneracy test.
    """
    x = ratio(dh, dh_pred, h_prev)
    return None if x is None else abs(1.0 - x)


def direction(dh: float, dh_pred: float, h_prev: float = 0.0) -> Direction | None:
    """Table 3: ``"degraded"`` when ΔH_i and ΔH_i^pred differ in sign, or agree in sign with
    x < 1; ``"improved"`` when they agree in sign with x > 1; None when x = 1 or undefined."""
    x = ratio(dh, dh_pred, h_prev)
    if x is None or x == 1.0:
        return None
    if np.sign(dh) != np.sign(dh_pred) or x < 1.0:
        return "degraded"
    return "improved"


def global_check(t_s: Sequence[float], h: Sequence[float], h_nom: Sequence[float],
                 rate_threshold: float) -> bool:
    """Eq. 6: ``∫₀ᵗ (H − H_nom) dt ≥ ΔH_threshold · t`` at the last sample (trapezoidal
    integral over the samples; H is a cost, so a positive integral is a shortfall of the
    constellation as a whole).

    Args:
        t_s: sample times from the start, s (increasing, first one the start).
        h, h_nom: actual and nominal global cost at those times.
        rate_threshold: ΔH_threshold, cost per second.
    """
    t = np.asarray(t_s, dtype=float)
    d = np.asarray(h, dtype=float) - np.asarray(h_nom, dtype=float)
    if t.size < 2 or t.shape != d.shape or not np.all(np.isfinite(d)):
        return False
    integral = float(np.sum(0.5 * (d[1:] + d[:-1]) * np.diff(t)))
    return integral >= rate_threshold * float(t[-1] - t[0])
