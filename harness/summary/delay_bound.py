"""Each fault's delay against the information bound (issue 41; docs/fdir.md, "The bound"):
where the sequential test runs, the per-image divergence a fault showed and the smallest delay
any test with the scan's false-alarm rate could have on it.

D = δ² / 2σ² (``gnc.sequential_test.kl_gaussian_shift``): δ is the faulty observer's mean
relative shift of the information ratio, (ΔH/ΔH^pred)/μ − 1, over its first whole window
after the onset (the window test's own ΔH and ΔH^pred, judged for every window of a declared
observer too), σ one image's nominal 1σ, √(σ_b² + σ_e²), as the scan held it there
(``FdirWindow.image_sigma``; the nearest window that has it).  With the nav's NIS, its
divergence per update too: (6/2)(λ − 1 − ln λ), λ the window's mean NIS over its 6 degrees
(``gnc.sequential_test.kl_chi2_scale``), the NIS scan's evidence.  The bound is log γ / D
images (``gnc.sequential_test.delay_bound``), D the larger of the two (one update an image:
both at ω_mid), γ = 1 / (2 L Φ(−c)) the scans' mean time to a false alarm (both scans hold
the same per-update probability), at least one image.  A fault whose effect grows (a
thruster's drift) has a D that grows with it: the window's mean then stands for its first
30 s.  Pure functions.
"""

from __future__ import annotations

from collections.abc import Sequence

from gnc.sequential_test import delay_bound, kl_chi2_scale, kl_gaussian_shift, scan_false_alarm
from ground.fdir.baselines import NIS_DOF
from harness.summary.scoring import FaultScore, Scores
from interfaces.contracts.messages import FdirWindow
from interfaces.contracts.timing import TIME_TOL_S


def first_faulty_window(fault: FaultScore, windows: Sequence[FdirWindow]) -> FdirWindow | None:
    """The fault's observer's first window wholly after its onset with a ratio and its
    nominal mean (None: none; a common-mode fault has no observer of its own)."""
    mine = [w for w in windows if w.spacecraft == fault.spacecraft
            and w.t_start_s >= fault.start_s - TIME_TOL_S and w.dh is not None
            and w.dh_pred and w.ratio_mean]
    return min(mine, key=lambda w: w.t_start_s) if mine else None


def scan_record_near(window: FdirWindow, windows: Sequence[FdirWindow]) -> FdirWindow | None:
    """The window of ``window``'s observer nearest it in time that holds the scan's record
    (``image_sigma``, ``scan_threshold``): itself when it does."""
    held = [w for w in windows if w.spacecraft == window.spacecraft
            and w.image_sigma is not None and w.scan_threshold is not None]
    return min(held, key=lambda w: abs(w.t_start_s - window.t_start_s)) if held else None


def fault_bound(fault: FaultScore, windows: Sequence[FdirWindow], image_period_s: float
                ) -> tuple[float, float | None, float] | None:
    """(D of the information nats per image, D of the NIS per update (None: no NIS summed),
    the delay bound s) of ``fault`` (module docstring): log γ / D images with D the larger of
    the two, the evidence the ground has at its fastest; None where no window after its
    onset has a ratio, or no window of its observer a scan record."""
    window = first_faulty_window(fault, windows)
    record = scan_record_near(window, windows) if window is not None else None
    if window is None or record is None:
        return None
    assert window.dh is not None and window.dh_pred and window.ratio_mean
    assert record.image_sigma is not None and record.scan_threshold is not None
    shift = window.dh / window.dh_pred / window.ratio_mean - 1.0
    divergence = kl_gaussian_shift(shift, record.image_sigma)
    nis = (kl_chi2_scale(window.nis_sum / (NIS_DOF * window.nis_updates), NIS_DOF)
           if window.nis_sum is not None and window.nis_updates else None)
    gamma = 1.0 / scan_false_alarm(record.scan_threshold)
    bound = delay_bound(gamma, max(divergence, nis or 0.0))
    return divergence, nis, max(bound, 1.0) * image_period_s


def with_delay_bounds(scores: Scores, windows: Sequence[FdirWindow],
                      image_period_s: float) -> Scores:
    """``scores`` with each fault's ``image_divergence`` and ``delay_bound_s`` where
    :func:`fault_bound` has them (unchanged where the scan did not run)."""
    per_fault = []
    for f in scores.per_fault:
        bound = fault_bound(f, windows, image_period_s)
        per_fault.append(f if bound is None else f.model_copy(update={
            "image_divergence": bound[0], "delay_bound_s": bound[2],
            **({"nis_divergence": bound[1]} if bound[1] is not None else {})}))
    return scores.model_copy(update={"per_fault": per_fault})
