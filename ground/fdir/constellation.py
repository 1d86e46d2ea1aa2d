"""The global check at runtime (paper Eq. 6; docs/fdir.md): the
constellation's information gain against its prediction, for faults no single observer
explains.

Over one FDI window, with ψ held at its start, the constellation's cost changes by
ΔH = Σ_i ΔH_i (the prior term does not move), so the windowed form of Eq. 6's integrand is the
constellation ratio X = Σ_i ΔH_i / Σ_i ΔH_i^pred.  Each observer's nominal ratio x_i has the
hardware model's N(μ_i, σ_i²) (``gnc/hardware_threshold.py``) and the observers' errors
are independent, so X ~ N(Σ μ_i P_i / Σ P_i, Σ σ_i² P_i² / (Σ P_i)²), P_i = ΔH_i^pred.

A constellation-level fault is one no single observer explains: X departs from its model by
more than the quantile τ_X, still does with the observer farthest from its own model left
out, and one factor common to every observer fits their ratios within their nominal spreads
(:func:`common_factor_fits`: a common cause scales them alike).  Otherwise that observer is
named as the explanation, and each observer's own test judges it.  A camera or
target-model error common to every observer (a wrong variance coefficient k, ``camera_calibration``)
is the example: every x_i moves together, and declaring each observer faulty would re-plan a
healthy constellation around itself.  Eq. 6's integral form (``metric.global_check``) is kept for
the cumulative record; this windowed test is what decides.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gnc.chi2 import chi2_quantile
from gnc.hardware_threshold import RatioModel

MIN_OBSERVERS = 3
"""Fewer judged observers than this give no constellation verdict (one left out must leave at
least two to compare)."""


@dataclass(frozen=True)
class ObserverGain:
    """One observer's window: ΔH_i, ΔH_i^pred and its nominal ratio model."""

    spacecraft: int
    dh: float
    dh_pred: float
    model: RatioModel


@dataclass(frozen=True)
class ConstellationVerdict:
    """The constellation ratio X, its nominal model and threshold, whether it is exceeded, and
    whether one observer alone explains the excess (``explained_by``: its number, else None)."""

    ratio: float
    model: RatioModel
    threshold: float
    exceeded: bool
    explained_by: int | None

    @property
    def common_mode(self) -> bool:
        """A fault no single observer explains."""
        return self.exceeded and self.explained_by is None


def constellation_ratio(gains: Sequence[ObserverGain]) -> tuple[float, RatioModel]:
    """X = Σ ΔH_i / Σ ΔH_i^pred and its nominal model (module docstring)."""
    pred = sum(g.dh_pred for g in gains)
    x = sum(g.dh for g in gains) / pred
    mean = sum(g.model.mean * g.dh_pred for g in gains) / pred
    var = sum((g.model.std * g.dh_pred) ** 2 for g in gains) / pred**2
    cam = sum((g.model.camera_std * g.dh_pred) ** 2 for g in gains) / pred**2
    pose = sum((g.model.pose_std * g.dh_pred) ** 2 for g in gains) / pred**2
    return x, RatioModel(mean, math.sqrt(var), math.sqrt(cam), math.sqrt(pose))


def _exceeds(gains: Sequence[ObserverGain], q: float) -> tuple[float, RatioModel, float, bool]:
    x, model = constellation_ratio(gains)
    tau = model.threshold(q)
    return x, model, tau, abs(1.0 - x) > tau


def constellation_check(gains: Sequence[ObserverGain], q: float) -> ConstellationVerdict | None:
    """The constellation verdict of one window at false-alarm probability ``q`` per test, or
    None with fewer than ``MIN_OBSERVERS`` judged observers (or no predicted gain)."""
    gains = [g for g in gains if g.dh_pred > 0.0 and math.isfinite(g.dh)]
    if len(gains) < MIN_OBSERVERS:
        return None
    x, model, tau, exceeded = _exceeds(gains, q)
    explained_by = None
    if exceeded:
        worst = max(gains, key=lambda g: abs(g.model.z(g.dh / g.dh_pred)))
        if not (_exceeds([g for g in gains if g is not worst], q)[3]
                and common_factor_fits(gains, q)):
            explained_by = worst.spacecraft
    return ConstellationVerdict(x, model, tau, exceeded, explained_by)


def common_factor_fits(gains: Sequence[ObserverGain], q: float) -> bool:
    """Whether one factor c common to every observer explains their ratios: x_i ≈ c μ_i
    within c σ_i (c by weighted least squares), by the χ² test of Σ ((x_i − c μ_i) / c σ_i)²
    with n − 1 degrees of freedom at false-alarm probability ``q``.  A common-mode fault scales
    every observer alike; one faulty observer, or several with different faults, do not."""
    x = np.array([g.dh / g.dh_pred for g in gains])
    mu = np.array([g.model.mean for g in gains])
    sd = np.array([max(g.model.std, 1e-12) for g in gains])
    c = float(np.sum(x * mu / sd**2) / np.sum(mu**2 / sd**2))
    if not c > 0.0:
        return False
    stat = float(np.sum(((x - c * mu) / (c * sd)) ** 2))
    return stat <= float(chi2_quantile(1.0 - q, len(gains) - 1))
