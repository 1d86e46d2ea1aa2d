"""Each fault's delay against the information bound (issue 41; docs/fdir.md, "Each fault
against the bound"): where the sequential test runs, the divergence per ω_mid step a fault
showed and the smallest delay any test with the scans' false-alarm rate could have on it.

Two streams of evidence reach the ground each ω_mid step, independent of each other: an image
and a nav update.

* The image's: D = δ² / 2σ² (``gnc.sequential_test.kl_gaussian_shift``), δ the faulty
  observer's mean relative shift of the information ratio, (ΔH/ΔH^pred)/μ − 1, over its first
  whole window after the onset while the fault lasts (the window test's own ΔH and ΔH^pred,
  judged for every window of a declared observer too), σ one image's nominal 1σ,
  √(σ_b² + σ_e²), as the scan held it (``FdirWindow.image_sigma``; the nearest window of the
  observer that has it).
* The nav update's: (6/2)(λ − 1), λ the same window's mean NIS over its 6 degrees
  (``gnc.sequential_test.kl_nis_growth``: the innovations' mean moved; the largest divergence
  that mean NIS allows, so the lowest bound); update by update, (NIS_k − 6)/2, whose sum from
  the onset is an unbiased estimate of the divergence the updates since carried.

The bound is the time from onset at which the divergence summed step by step first reaches
log γ, γ = 1 / (2 L Φ(−c)) the scans' mean time to a false alarm (both hold the same
probability per step; Lorden 1971: no test as quick to false-alarm has a smaller worst-case
mean delay), at least one step: with the nav's updates (``nis``), the image's D each step
plus each update's own; without them, log γ / D steps (``gnc.sequential_test.delay_bound``) with D
the sum of the window's two.  The nav's updates count only where the window's NIS test failed
(:func:`nis_moved`); summed update by update, with the image's divergence of the window each
falls in (:func:`image_divergences`), the bound follows a fault whose effect grows (a
thruster's drift).  Where the NIS did not move, the image's part is the first whole window's
mean, which for a growing fault (a pointing error building up) says more than its first
seconds show, so its bound is low.  Pure functions.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from gnc.sequential_test import delay_bound, kl_gaussian_shift, kl_nis_growth, scan_false_alarm
from ground.fdir.baselines import NIS_DOF
from harness.summary.scoring import Scores
from interfaces.contracts.messages import FdirWindow, StateEstimate
from interfaces.contracts.scenario import Fault
from interfaces.contracts.timing import TIME_TOL_S


@dataclass(frozen=True)
class FaultBound:
    """A fault's divergences per step (nats: the image's, the nav update's, None: no NIS
    summed) and its delay bound (s)."""

    image: float
    nis: float | None
    delay_s: float


def first_faulty_window(fault: Fault, windows: Sequence[FdirWindow]) -> FdirWindow | None:
    """The fault's observer's first window wholly after its onset, begun while it lasts, with a
    ratio and its nominal mean (None: none; a common-mode fault has no observer of its own)."""
    mine = [w for w in windows if w.spacecraft == fault.spacecraft
            and w.t_start_s >= fault.start_s - TIME_TOL_S
            and (fault.end_s is None or w.t_start_s < fault.end_s)
            and w.dh is not None and w.dh_pred and w.ratio_mean]
    return min(mine, key=lambda w: w.t_start_s) if mine else None


def scan_record_near(window: FdirWindow, windows: Sequence[FdirWindow]) -> FdirWindow | None:
    """The window of ``window``'s observer nearest it in time that holds the scan's record
    (``image_sigma`` above 0, ``scan_threshold``): itself when it does."""
    held = [w for w in windows if w.spacecraft == window.spacecraft
            and w.image_sigma and w.scan_threshold is not None]
    return min(held, key=lambda w: abs(w.t_start_s - window.t_start_s)) if held else None


NisSeries = Mapping[int, Sequence[tuple[float, float]]]
"""Each observer's nav updates: (time s, NIS), in time order."""


def nis_series(estimates: Iterable[StateEstimate]) -> dict[int, list[tuple[float, float]]]:
    """Each observer's nav updates with a NIS, in time order, from its estimates."""
    out: dict[int, list[tuple[float, float]]] = {}
    for m in sorted(estimates, key=lambda m: m.t_sim):
        if m.nis is not None:
            out.setdefault(m.spacecraft, []).append((m.t_sim, m.nis))
    return out


def image_divergences(fault: Fault, windows: Sequence[FdirWindow], sigma: float
                      ) -> list[tuple[float, float, float]]:
    """The image's divergence per step in each window of ``fault``'s observer that ends after
    its onset and has a ratio: (start s, end s, δ_w² / 2σ²), δ_w the window's own mean
    shift (the window the onset falls in holds images from before it too)."""
    return [(w.t_start_s, w.t_end_s, kl_gaussian_shift(
                w.dh / w.dh_pred / w.ratio_mean - 1.0, sigma))
            for w in windows if w.spacecraft == fault.spacecraft
            and w.t_end_s > fault.start_s and w.dh is not None and w.dh_pred and w.ratio_mean]


def summed_bound_s(fault: Fault, image: Sequence[tuple[float, float, float]],
                   updates: Sequence[tuple[float, float]], log_gamma: float, step_s: float
                   ) -> float | None:
    """The time from ``fault``'s onset (s) at which the image's divergence of the window each
    nav update falls in (``image``: :func:`image_divergences`) plus each update's
    (NIS_k − 6)/2 since the onset first sum to ``log_gamma``, at least one step; None when
    they never do while the fault lasts."""
    total = 0.0
    for t, nis in updates:
        if t < fault.start_s - TIME_TOL_S or (fault.end_s is not None and t > fault.end_s):
            continue
        total += next((d for a, b, d in image if a <= t < b), 0.0) + (nis - NIS_DOF) / 2.0
        if total >= log_gamma:
            return max(t - fault.start_s, step_s)
    return None


def fault_bound(fault: Fault, windows: Sequence[FdirWindow], step_s: float,
                updates: Sequence[tuple[float, float]] = ()) -> FaultBound | None:
    """``fault``'s divergences and delay bound (module docstring; ``step_s``: the ω_mid
    period, s; ``updates``: its observer's nav updates, (time s, NIS)); None where no window
    after its onset has a ratio, no window of its observer a scan record, the window shows no
    divergence, or the updates' sum never reached log γ while the fault lasted."""
    window = first_faulty_window(fault, windows)
    record = scan_record_near(window, windows) if window is not None else None
    if window is None or record is None:
        return None
    assert window.dh is not None and window.dh_pred and window.ratio_mean
    assert record.image_sigma and record.scan_threshold is not None
    image = kl_gaussian_shift(window.dh / window.dh_pred / window.ratio_mean - 1.0,
                              record.image_sigma)
    nis = (kl_nis_growth(window.nis_sum / window.nis_updates, NIS_DOF)
           if window.nis_sum is not None and window.nis_updates else None)
    total = image + (nis or 0.0)
    if not total > 0.0:
        return None
    gamma = 1.0 / scan_false_alarm(record.scan_threshold)
    if not nis_moved(window):
        return (FaultBound(image, nis, max(delay_bound(gamma, image), 1.0) * step_s)
                if image > 0.0 else None)
    if not updates:
        return FaultBound(image, nis, max(delay_bound(gamma, total), 1.0) * step_s)
    summed = summed_bound_s(fault, image_divergences(fault, windows, record.image_sigma),
                            updates, math.log(gamma), step_s)
    return FaultBound(image, nis, summed) if summed is not None else None


def nis_moved(window: FdirWindow) -> bool:
    """Whether the window's NIS test failed (its sum beyond its χ²(6N) limit): only then do
    the nav's updates count in the bound, since summed update by update a nominal NIS's noise
    (1.7 nats a step) would reach log γ by chance and set a bound below any test's reach."""
    return (window.nis_sum is not None and window.nis_limit is not None
            and window.nis_sum > window.nis_limit)


def with_delay_bounds(scores: Scores, faults: Sequence[Fault], windows: Sequence[FdirWindow],
                      step_s: float, nis: NisSeries | None = None) -> Scores:
    """``scores`` (per fault, in the order of ``faults``) with each fault's
    ``image_divergence``, ``nis_divergence`` and ``delay_bound_s`` where :func:`fault_bound`
    has them (unchanged where the scan did not run); ``nis``: the nav updates."""
    per_fault = []
    for score, fault in zip(scores.per_fault, faults, strict=True):
        bound = fault_bound(fault, windows, step_s, (nis or {}).get(fault.spacecraft, ()))
        per_fault.append(score if bound is None else score.model_copy(update={
            "image_divergence": bound.image, "delay_bound_s": bound.delay_s,
            **({"nis_divergence": bound.nis} if bound.nis is not None else {})}))
    return scores.model_copy(update={"per_fault": per_fault})
