"""The adaptive fault threshold (paper Eq. 11-12), its calibrated floor, and the persistence
rule (docs/fdir.md: a fault is declared when H_m,i > τ_i for a configurable number of windows, as
cFS Limit Checker's fails-before-action).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from gnc.fdi_metric import metric
from gnc.hardware_threshold import RatioModel
from gnc.twin import TwinModel, perturbed_boresights, sample_stride
from gnc.window_test import HardwareThreshold, floor_guard
from interfaces.contracts.timing import TIME_TOL_S


def adaptive_threshold(dh_samples: Sequence[float], dh_pred: float, h_prev: float = 0.0,
                       floor: float = 0.0) -> float | None:
    """τ_i (Eq. 11-12) from the changes ΔH_i^(k) of K sampled near-nominal pointings (the
    ε-neighbourhood of the max-variance POI): Eq. 11 picks the sample set S' whose cost is the
    closest to the prediction without equalling it, so τ_i is the smallest non-zero metric
    ``|1 − ΔH^(k)/ΔH^pred|`` over the samples; then ``max(τ_i, floor)``.

    Returns None when the prediction is degenerate (no threshold, no decision).  When every
    sample equals the prediction the floor alone is returned.
    """
    values = [metric(dh, dh_pred, h_prev) for dh in dh_samples]
    if any(v is None for v in values) or metric(dh_pred, dh_pred, h_prev) is None:
        return None
    nonzero = [v for v in values if v is not None and v > 0.0]
    tau = min(nonzero) if nonzero else 0.0
    return max(tau, floor)


def calibrate_floor(nominal_metrics: Sequence[float], false_alarm_rate: float,
                    persistence: int) -> float:
    """The threshold floor for a target false-alarm probability per FDI window.

    With a fault declared after ``persistence`` = N consecutive exceedances, and windows treated
    as independent, a per-window exceedance probability q gives false alarms at rate ≈ q^N; so
    q = rate^(1/N) and the floor is the (1 − q) empirical quantile of the nominal metrics
    (linear interpolation).  Nominal windows are rarely independent (slow geometry), so the
    achieved rate is measured on nominal runs, not promised by this formula.

    Raises:
        ValueError: no finite samples, a rate outside (0, 1), or persistence < 1.
    """
    if not 0.0 < false_alarm_rate < 1.0:
        raise ValueError(f"false_alarm_rate must be in (0, 1), got {false_alarm_rate!r}")
    if persistence < 1:
        raise ValueError(f"persistence must be >= 1, got {persistence!r}")
    m = np.asarray([v for v in nominal_metrics if v is not None and math.isfinite(v)])
    if m.size == 0:
        raise ValueError("no finite nominal metric samples to calibrate from")
    q = false_alarm_rate ** (1.0 / persistence)
    return float(np.quantile(m, 1.0 - q))


@dataclass
class Persistence:
    """Exceedance counter per spacecraft: ``update`` returns True on the window that brings the
    exceedances among the last ``window`` decided windows to ``count``, itself exceeding (None:
    ``count`` in a row), once per episode: the episode ends when that no longer holds.  A
    window without a decision (None: missing or degenerate) neither counts nor resets.  An
    episode declared at a time (``declare(at_s=...)``: the sequential test's crossing) is not
    ended by a window that began before it and passed on the whole (:meth:`counted`)."""

    count: int = 3
    window: int | None = None
    _hits: dict[int, list[bool]] = field(default_factory=dict)
    _declared: set[int] = field(default_factory=set)
    _crossed_s: dict[int, float] = field(default_factory=dict)
    """episodes declared at a time (s), until a window that began at or after it"""

    def declared(self, spacecraft: int) -> bool:
        """Whether a fault of ``spacecraft`` is declared and its episode still going on."""
        return spacecraft in self._declared

    def declare(self, spacecraft: int, at_s: float | None = None) -> None:
        """A fault of ``spacecraft`` declared on other grounds (one decisive window, or a
        scan's crossing at ``at_s``, s): its episode goes on while its windows keep exceeding,
        without another declaration."""
        self._declared.add(spacecraft)
        self._hits[spacecraft] = [True] * (self.window or self.count)
        if at_s is not None:
            self._crossed_s[spacecraft] = at_s

    def counted(self, spacecraft: int, exceeded: bool | None, window_start_s: float
                ) -> bool | None:
        """What a window of ``spacecraft`` starting at ``window_start_s`` (s) with verdict
        ``exceeded`` counts: its verdict, except that one begun before the crossing that
        declared the episode, not exceeded on the whole (the change began late in it),
        counts as no decision (None)."""
        crossed = self._crossed_s.get(spacecraft)
        if crossed is not None and window_start_s < crossed - TIME_TOL_S:
            return exceeded or None
        self._crossed_s.pop(spacecraft, None)
        return exceeded

    def update(self, spacecraft: int, exceeded: bool | None) -> bool:
        if exceeded is None:
            return False
        n = self.window or self.count
        hits = self._hits.setdefault(spacecraft, [])
        hits.append(exceeded)
        del hits[:-n]
        if not (exceeded and sum(hits) >= self.count):
            self._declared.discard(spacecraft)
            return False
        if spacecraft in self._declared:
            return False
        self._declared.add(spacecraft)
        return True


def sampled_threshold(twin: TwinModel, positions: np.ndarray, boresights: np.ndarray,
                      psi: np.ndarray, phi: np.ndarray, h_prev: float, eps_rad: float,
                      samples: int, floor: float, rng: np.random.Generator) -> float | None:
    """τ_i (Eq. 11-12) of one window: ``samples`` pointings within ``eps_rad`` of the planned
    ones for (at most ``SAMPLED_IMAGES``, evenly spread) planned images, each compared with the
    prediction for the same images; floored at ``floor``."""
    k = sample_stride(len(positions))
    pos, bore = positions[::k], boresights[::k]
    ref = twin.predicted(pos, bore, psi, phi)
    tilted = perturbed_boresights(bore, eps_rad, len(bore), rng, draws=samples)
    draws = twin.predicted_each(pos, np.split(tilted, samples), psi, phi)
    # the subset holds about 1/k of the window's gain
    return adaptive_threshold(draws, ref, h_prev / k, floor)


@dataclass(frozen=True)
class WindowThreshold:
    """The thresholds of one observer's window: the hardware model (its ratio distribution and
    quantile), Eq. 11-12's sampled τ (unfloored), and the one in force, ``tau``, with what set
    it (``by``: the selected threshold, or the floor guard where the selected one is below it).
    ``tau`` is None when the selected threshold is undefined (degenerate prediction)."""

    model: RatioModel | None
    model_tau: float | None
    sampled: float | None
    tau: float | None
    by: Literal["model", "sampled", "floor"] | None

    @classmethod
    def choose(cls, hardware: HardwareThreshold | None, sampled: float | None,
               name: Literal["model", "sampled"], floor: float) -> WindowThreshold:
        """The thresholds of the window, the one ``name`` selects in force, raised to the floor
        guard ``floor`` where it is below (``gnc.window_test.floor_guard``)."""
        model, model_tau = (hardware.model, hardware.quantile) if hardware else (None, None)
        if name == "model":
            if hardware is None:
                return cls(None, None, sampled, None, None)
            return cls(model, model_tau, sampled, hardware.tau,
                       "floor" if hardware.floored else "model")
        if sampled is None:
            return cls(model, model_tau, None, None, None)
        tau, floored = floor_guard(sampled, floor)
        return cls(model, model_tau, sampled, tau, "floor" if floored else "sampled")
