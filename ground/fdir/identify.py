"""Fault identification: which part of a faulty observer failed (docs/fdir.md, "Information cost
and FDIR": identification beyond the paper's 1-DOF example, Eq. 17-21).

Once H_m,i has isolated observer i, the ground weighs four pieces of evidence from one FDI
window, all from telemetry it already receives:

* **Where the camera really was.**  Each image measures every visible POI with precision
  σ⁻¹ = β / (k d²) (Eq. 5 with the camera health β of Eq. 21), so d²/β = 1/(k σ⁻¹).  On a
  spherical target of radius R, d² = |c|² + R² − 2 c·s is affine in the POI position s, so a
  fit k σ⁻¹ (a + g·s) ≈ 1 gives g = −2c/β and a = (|c|² + R²)/β, hence
  β²|g|²/4 − aβ + R² = 0: two roots, one camera outside the sphere (the answer) and its
  inverse point inside it (:func:`locate_camera`).  The camera's position and β come out of
  the image itself, independent of the observer's navigation.
* **Where the observer says it was**: its nav estimate and its attitude estimate (reported
  boresight and pointing error), against the plan.
* **The gradient test**: ∂H_i/∂p_i times the pose deviation predicts the change of H_i that
  motion alone explains.  The twin carries this to all orders: it re-evaluates ΔH_i at the
  reported pose, and at the located camera positions, and :func:`explained_fraction` says how
  much of the gap ΔH_i − ΔH_i^pred each pose accounts for.
* **The seen set**: the POIs an image saw against those the reported pose would see, and the
  boresight they show (``ground/fdir/boresight.py``: the edge of the field of view across the
  target, from the located camera), against the one the attitude estimate reports.
* **The Δv it commands while holding its PRO**: a PRO is natural motion, so a healthy
  observer on station spends almost nothing (≈1e-5 m/s² of commanded Δv per second); one that
  fights a force it does not model (a thruster leak) spends what the force costs.

:func:`classify` turns the evidence into a class:

==========================================================  ================
evidence (in this order)                                    class
==========================================================  ================
β̂ off 1 (information short by a uniform factor), by more   ``camera``
than beta_tol and ``BETA_SE_MARGIN`` standard errors
nav off plan, the camera on it (within half the tolerance,  ``state_sensor``
or ``SE_MARGIN`` standard errors of the located camera
while beyond them off the nav), or off it the other way
(``offset_alignment`` < −0.5)
pointing error reported, and the pose explains the ΔH gap   ``actuator``
(or there is none: the information test passed)
the seen POIs show a boresight > 2 × pointing_tol_deg off    ``camera``
(and ``SE_MARGIN`` standard errors of the located camera)
Δv commanded while holding, above ``dv_rate_tol_mps2``      ``actuator``
camera not where nav says, by more than nav is off plan,
and dragged off the plan ahead of the nav the same way      ``actuator``
camera not where nav says, by more than nav is off plan     ``state_sensor``
(and ``SE_MARGIN`` standard errors of the located camera)
nav off plan (the observer knows it is not on its orbit)    ``actuator``
dragged off the plan ahead of the nav the same way, camera
off nav by more than half the position tolerance            ``actuator``
seen set not what the reported pose would see, with the     ``camera``
camera located where the nav says (the nav right)
==========================================================  ================

"The same way" (``offset_alignment`` > 0.5) counts only where the located camera's offset from
the plan exceeds the standard error of its fixes (a camera on the plan, within its noise, has
no direction), and "ahead of the nav" is the camera the farther off the plan: a leak drags the
truth and the nav follows, lagging it, while a biased nav walks off the plan ahead of the truth
it steers (identify campaign, seeds 201-205: four nav biases named ``actuator`` on cosines of
0.65-0.73, two with the camera inside its noise, two with it nearer the plan than the nav).
The seen set names the camera only where the nav is right: with the camera located off the nav
by more than half the tolerance and ``SE_MARGIN`` standard errors of the fixes, the nav's
error alone changes the set the reported pose would see (two nav biases walking off the plan
were named ``camera`` on seen sets of 0.78-0.79).

The comparison of the two distances separates a biased nav sensor (the observer flies its
plan by its nav, so nav stays on plan and the camera is off by the bias) from an orbit
actuator fault (nav follows the deviation off plan, lagging it by what the unmodelled force
does in the filter).  That comparison alone fails for weak thruster leaks that the controller
holds near the plan: nav then stays within the filter lag of the plan and the lag looks like a
bias (the paper campaign misnamed 1 of its first 32 leaks so).  The Δv the observer spends on
station tells them apart first: the leak costs ≈4e-3 m/s² per unit of the maximum thrust
fraction, a nav bias only the transient of moving onto the offset orbit (2.6e-4 in the
window of a 3 m step, 1e-4 after).  With short windows the Δv has not built up when a leak is
declared; the directions separate them then: a leak drags the truth off the plan and the nav
follows it the same way (``offset_alignment`` > 0.5, the cosine between the located camera's
and the nav's offsets from the plan), while a biased nav sits on one side of the plan and the
truth, steered by it, on the other (a negative cosine).  In a bias's first tens of seconds the
filter is still absorbing the step: the nav walks off the plan while the spacecraft, steered
by it only slowly, is still on it, so the camera located from the images sits on the plan.
That comes before the Δv spent: the guidance moving the observer onto the biased orbit spent
1e-3 m/s² in the window of a 4.6 m step (hard campaign, late-nav-bias-0001), above the
bound a leak is named by; a leak never leaves the truth on the plan with the nav off it (the
nav lags the truth).  It comes before the pointing error too: the attitude loop aims from the
nav, so when the nav jumps the pointing error it reports jumps with it (0.77-1.59° in the
identifying windows of three late nav biases, with the pose explaining 0.50-0.94 of the ΔH
gap), while a pointing fault leaves the nav on its plan (at most 0.04 m off it in the 40
identifying windows of pointing faults in the paper and hard campaigns).

A window that fails only the nav's NIS test (ground/fdir/consistency.py) is not called
``state_sensor``: the NIS sees an orbit actuator fault's unmodelled force as soon as a biased
sensor's step, often before the truth has moved off the plan by more than the camera fixes'
noise, and with the nav still near the plan the camera-off-nav fallback would name the sensor.
Such a fault is declared unidentified and identified on a later window of the episode, when its
other tests or its geometry speak (a leak: Δv spent, offsets the same way; a bias: the nav off
the plan).  More generally, a window whose NIS test fails while the nav is still on its plan
(``NAV_ON_PLAN_M``) and the camera is located off it by more than half the position tolerance
names no class but ``actuator``: the truth has moved and the nav has not followed it yet (a
leak's first seconds, a state disturbance's jump; a settled nav bias shows the same geometry,
but its NIS passes).  The identify campaign named two leaks and a jump so ``state_sensor`` or
``camera``; on their next window the nav had followed the truth the same way (cosine > 0.99).

(``link`` and ``data_integrity`` are decided by the FDIR app from missing telemetry and from
the reported H_i.)  Pure functions; the app gathers the inputs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace

import numpy as np
import numpy.typing as npt

from gnc.hardware_threshold import clipped_noise_moments
from gnc.infocost import visibility
from gnc.twin import TwinModel, sample_stride
from gnc.window_test import Observation, WindowPose
from ground.fdir.boresight import boresight_offset
from ground.fdir.trilateration import least_squares, least_squares_each
from interfaces.contracts.scenario import FdirSettings

FloatArray = npt.NDArray[np.float64]

MIN_POIS = 12
"""Fewer POIs in an image than this give no camera fix (4 unknowns, noisy precisions)."""

BETA_SE_MARGIN = 5.0
"""β̂ is called off 1 only beyond this many standard errors of its median too
(``Evidence.beta_se``).  With a 12° camera and 50% precision noise the images' β scatter so
much that healthy windows' medians fall 0.8-1.17, outside ``beta_tol``; in 360 synthetic
healthy windows (12° and 20° cameras, noise 5-50%) the median was at most 3.8 of them off."""

SE_MARGIN = 3.0
"""The boresight the seen POIs show counts only beyond this many standard errors of the
located camera's median offset too (``Evidence.camera_se_deg``): with a 12° camera and 50%
precision noise the camera is located 1.4 m off (p90), which turns the boresight fitted from
it by several degrees.  In 360 synthetic healthy windows the located camera was at most 3.3
standard errors off.  The camera-off-nav rule's ``state_sensor`` verdict is guarded so too:
a 12° camera misaligned by 4-10° at 50% noise is located 0.5-2.5 m off its nav, within 3
standard errors (0.6-1.7 m each), and 13 of the 16 such faults of the beyond campaign were
named ``state_sensor``.  The ``actuator`` verdicts read from the same distances are not guarded: a
leak drags the camera during the window, which widens the spread of its offsets, and a guard
of 3 standard errors lost the first window of 8 of 32 paper_fig23 leaks at 5% noise."""

MIN_FIXES = 5
"""Fewer located images than this in a window give no camera evidence (one fix is noisy:
tenths of a metre and a few percent of β per image with a 12° camera at 20 m)."""


@dataclass(frozen=True)
class CameraFix:
    """A camera position (LVLH, m) and health β located from one image."""

    position_m: FloatArray
    beta: float


def locate_camera(poi_pos: npt.ArrayLike, precision: npt.ArrayLike, k: float,
                  radius_m: float, noise_frac: float = 0.0,
                  seen: npt.ArrayLike | None = None) -> CameraFix | None:
    """Trilaterate the camera from one image of a spherical target (module docstring).

    The measured σ⁻¹_j = β w_j / (k d_j²) carries the camera's multiplicative noise
    w_j = max(0, 1 + ν ε_j), so the rows k σ⁻¹_j [1, s_j] regressed on 1 leave the residuals
    1 − w_j: zero-mean, of one spread.  (Fitting d²/β = 1/(k σ⁻¹) itself does not: a POI whose
    w came out near 0 gives a value without bound; at ν = 50% that fit put the camera metres
    off and β at 0.1-0.3.)  The noise in the regressors shrinks the fit by
    f = E[w] / E[w²] (errors in variables); dividing it out leaves β unbiased, and the
    position, which is a ratio of the fitted terms, does not depend on it.

    The least squares are solved by their normal equations
    (``ground.fdir.trilateration.least_squares``).

    Args:
        poi_pos: positions (n, 3) of the POIs the image saw, target frame (LVLH), m, on the
            sphere of radius ``radius_m`` about the origin; with ``seen``, every POI's (M, 3).
        precision: their measured σ⁻¹ (n,), > 0.
        k: the camera's variance coefficient (σ = k d², Eq. 5), m⁻².
        radius_m: the target's radius R, m.
        noise_frac: ν, the 1σ multiplicative noise of a measured precision (the camera's
            spec, ``[camera] noise_frac``).
        seen: the indices (n,) into ``poi_pos`` of the POIs the image saw (None: ``poi_pos``
            are they).

    Returns:
        The fix, or None when the image saw fewer than ``MIN_POIS`` POIs or the fit is
        degenerate (POIs near a plane, no root outside the sphere).

    Raises:
        ValueError: when the positions, indices and precisions do not go together.
    """
    p = np.ascontiguousarray(precision, dtype=float)
    if p.ndim == 1 and len(p) < MIN_POIS:
        return None
    s = np.ascontiguousarray(poi_pos, dtype=float)
    index = np.arange(len(s)) if seen is None else np.ascontiguousarray(seen)
    return camera_fix(least_squares(s, index, k * p, MIN_POIS), radius_m, noise_frac)


def camera_fix(coef: npt.NDArray[np.float64] | None, radius_m: float, noise_frac: float
               ) -> CameraFix | None:
    """The camera fix of the trilateration's fitted θ = [a, g] (:func:`locate_camera`; None:
    no fit): its errors-in-variables shrinkage divided out, the root outside the sphere of
    radius ``radius_m`` (m).  None when there is no such root."""
    if coef is None:
        return None
    m1, var = clipped_noise_moments(noise_frac)
    coef = coef * (m1 * m1 + var) / m1
    a, g = float(coef[0]), coef[1:]
    gg = float(g @ g)
    if not (gg > 0.0 and a > 0.0):
        return None
    root = math.sqrt(max(a * a - gg * radius_m**2, 0.0))
    beta = 2.0 * (a + root) / gg  # the larger root: |c| = β|g|/2 > R (the other is inside)
    c = -0.5 * beta * g
    if not (np.linalg.norm(c) > radius_m and math.isfinite(beta)):
        return None
    return CameraFix(c, beta)


def explained_fraction(dh: float, dh_pred: float, dh_alt: float) -> float | None:
    """How much of the gap ΔH_i − ΔH_i^pred an alternative pose's ΔH_alt accounts for:
    1 − |ΔH_i − ΔH_alt| / |ΔH_i − ΔH_i^pred| (1: all of it, ≤ 0: none).  None without a gap."""
    gap = abs(dh - dh_pred)
    if not gap > 0.0:
        return None
    return 1.0 - abs(dh - dh_alt) / gap


def seen_overlap(seen: npt.ArrayLike, expected: npt.ArrayLike) -> float | None:
    """Jaccard overlap |A ∩ B| / |A ∪ B| of two POI index sets; None when both are empty."""
    a, b = set(np.asarray(seen).tolist()), set(np.asarray(expected).tolist())
    union = len(a | b)
    return len(a & b) / union if union else None


@dataclass(frozen=True)
class Evidence:
    """One FDI window's identification evidence for one observer (medians over its images;
    None where not available).

    Attributes:
        beta_hat: camera health from the images (1 nominal).
        camera_vs_nav_m: distance between the median camera position from the images and the
            nav estimate's (median of the per-image vector differences), m.
        nav_vs_plan_m: median distance of the nav estimate from the plan, m.
        pointing_error_deg: median pointing error the attitude estimate reports, deg.
        seen_overlap: median Jaccard overlap of the seen POIs with those the reported pose
            (nav position, reported boresight) would see.
        explained_reported: :func:`explained_fraction` of the twin at the reported pose.
        explained_located: the same at the located camera positions (reported boresight).
        dv_rate_mps2: commanded Δv per second over the window's time holding the PRO
            (guidance mode ``hold``), m/s².
        offset_alignment: cosine between the located camera's and the nav's median offsets
            from the plan (None when either is under ``MIN_OFFSET_M``).
        camera_vs_plan_m: length of the located camera's median offset from the plan, m.
        camera_offset_deg: median angle between the reported boresight and the one the seen
            POIs show, from the located camera positions (``ground/fdir/boresight.py``), deg.
        beta_se: standard error of ``beta_hat`` from the spread of the images' own β
            (:func:`median_se`).
        camera_se_m: standard error of the located camera's median offset from the plan
            (per axis, :func:`median_se`), m.
        camera_se_deg: the same as the angle it subtends at the target's near surface, deg.
    """

    beta_hat: float | None = None
    camera_vs_nav_m: float | None = None
    nav_vs_plan_m: float | None = None
    pointing_error_deg: float | None = None
    seen_overlap: float | None = None
    explained_reported: float | None = None
    explained_located: float | None = None
    dv_rate_mps2: float | None = None
    offset_alignment: float | None = None
    camera_vs_plan_m: float | None = None
    camera_offset_deg: float | None = None
    beta_se: float | None = None
    camera_se_m: float | None = None
    camera_se_deg: float | None = None

    def as_dict(self) -> dict[str, float]:
        """The evidence present, by name (for the bus and summary.json)."""
        return {k: v for k, v in asdict(self).items() if v is not None}


@dataclass(frozen=True)
class Tolerances:
    """Nominal bounds of the evidence (``FdirSettings``: beta_tol, position_tol_m,
    pointing_tol_deg, overlap_tol, explained_min, dv_rate_tol_mps2)."""

    beta: float
    position_m: float
    pointing_deg: float
    overlap: float
    explained: float
    dv_rate_mps2: float

    @classmethod
    def of(cls, fdir: FdirSettings) -> Tolerances:
        return cls(fdir.beta_tol, fdir.position_tol_m, fdir.pointing_tol_deg, fdir.overlap_tol,
                   fdir.explained_min, fdir.dv_rate_tol_mps2)


def classify(ev: Evidence, tol: Tolerances, failed: Sequence[str] | None = None
             ) -> str | None:
    """The fault class the evidence points to (module docstring table), or None when nothing
    stands out.  ``failed``: the detector's tests the window failed (None: not known).  A
    window failed by the nav's NIS test alone is not called ``state_sensor``, and one whose
    NIS test fails while the truth has left a nav still on its plan names no class but
    ``actuator`` (module docstring).  A window whose information test passed has no ΔH gap
    for the pose to explain."""
    failed = ["information"] if failed is None else list(failed)
    cls = _evidence_class(ev, tol, gap="information" in failed)
    if cls == "state_sensor" and failed == ["nis"]:
        return None
    if cls != "actuator" and "nis" in failed and _truth_not_followed(ev, tol):
        return None
    return cls


def classify_part(ev: Evidence, tol: Tolerances, failed: Sequence[str] | None = None,
                  nis_span: int | None = None) -> str | None:
    """:func:`classify` for the evidence of part of a window (the images since a change the
    sequential test estimated; docs/fdir.md, "Identification after a crossing"), which names
    no class but ``state_sensor`` while the nav is off its plan by more than half
    ``position_tol_m`` unless the located camera is off it too, beyond half of it and
    ``SE_MARGIN`` standard errors of its fixes (the spacecraft moved, as after a state
    disturbance).  Otherwise it may be a nav sensor's step being absorbed, the nav walking
    off the plan ahead of the spacecraft it steers, and on ten images the fixes' standard
    error (0.15-0.25 m) is too wide for the rules that tell it from a camera fault or a
    leak.  On the identify campaign's paper set-up, replayed, 6 of 12 nav biases were named
    ``camera`` (a seen set not the reported pose's) or ``actuator`` (the Δv of moving onto
    the biased orbit, or the nav off the plan) 12-59 s after onset, with the nav 0.40-0.53 m
    off the plan and the camera 0.09-0.34 m at standard errors of 0.15-0.25 m.  The windows,
    or a later part, name it.

    ``nis_span``: the fault was declared by the nav's NIS scan, crossing over this many
    nav updates (None: declared otherwise).  A crossing over ``STEP_SPAN`` updates or fewer
    is a step: a sudden innovation, the truth or the nav sensor jumped.  While the NIS still
    fails, the nav walking off the plan (beyond ``NAV_ON_PLAN_M``) with the located camera
    not moved and nearer the plan than the nav is the sensor's step: a jump of the truth (a
    state disturbance) moves the camera by the step at once, ahead of the nav that follows
    it (:func:`_sensor_step`).  A longer crossing is a ramp, named ``actuator`` while the
    NIS still fails with the nav on its plan (:func:`_force_ramp`)."""
    half = tol.position_m / 2.0
    camera_moved = (ev.camera_vs_plan_m or 0.0) > half + SE_MARGIN * (ev.camera_se_m or 0.0)
    step = nis_span is not None and nis_span <= STEP_SPAN
    if step and not camera_moved and _sensor_step(ev, failed):
        return "state_sensor"
    if nis_span is not None and not step and _force_ramp(ev, failed):
        return "actuator"
    cls = classify(ev, tol, failed)
    if cls != "state_sensor" and (ev.nav_vs_plan_m or 0.0) > half and not camera_moved:
        return None
    return cls


def _evidence_class(ev: Evidence, tol: Tolerances, gap: bool = True) -> str | None:
    if ev.beta_hat is not None and abs(ev.beta_hat - 1.0) > max(
            tol.beta, BETA_SE_MARGIN * (ev.beta_se or 0.0)):
        return "camera"
    nav_plan, camera_nav = ev.nav_vs_plan_m or 0.0, ev.camera_vs_nav_m or 0.0
    half = tol.position_m / 2.0
    align = _alignment(ev)
    if nav_plan > tol.position_m and ((ev.camera_vs_plan_m or math.inf) < half
                                      or (align or 0.0) < -SAME_WAY or _nav_left_camera(ev)):
        return "state_sensor"  # the nav left the plan; the spacecraft did not, or the other way
    explained = [e for e in (ev.explained_reported, ev.explained_located) if e is not None]
    pose_explains = not gap or not explained or max(explained) >= tol.explained
    if (ev.pointing_error_deg or 0.0) > tol.pointing_deg and pose_explains:
        return "actuator"
    if (ev.camera_offset_deg or 0.0) > (2.0 * tol.pointing_deg  # beyond the fit's spread
                                        + SE_MARGIN * (ev.camera_se_deg or 0.0)):
        return "camera"  # it looks elsewhere than its attitude says: misaligned in its mount
    if (ev.dv_rate_mps2 or 0.0) > tol.dv_rate_mps2:
        return "actuator"
    dragged = (align or 0.0) > SAME_WAY and (ev.camera_vs_plan_m or 0.0) > nav_plan
    if camera_nav > tol.position_m and camera_nav > nav_plan:
        if dragged:
            return "actuator"
        if _beyond_fixes(ev, camera_nav):
            return "state_sensor"
    if nav_plan > tol.position_m:
        return "actuator"
    if dragged and camera_nav > half:
        return "actuator"  # the truth dragged off the plan ahead of the nav: a leak
    nav_wrong = camera_nav > half and _beyond_fixes(ev, camera_nav)
    if ev.seen_overlap is not None and ev.seen_overlap < tol.overlap and not nav_wrong:
        return "camera"
    return None


STEP_SPAN = 2
"""A NIS scan crossing on this many nav updates or fewer is a step (a sudden innovation):
on the identify and paper campaigns, replayed, every nav bias and state disturbance the NIS
scan declared crossed on one update, and 44 of 51 thruster leaks on 4-16."""


def _sensor_step(ev: Evidence, failed: Sequence[str] | None) -> bool:
    """Whether, after a NIS step, the nav has walked off its plan (``NAV_ON_PLAN_M``) while
    the spacecraft it steers stayed nearer the plan than the nav, with the NIS still failing:
    the filter absorbing a sensor's step (:func:`classify_part`)."""
    nav_plan = ev.nav_vs_plan_m or 0.0
    return ("nis" in (failed or []) and nav_plan > NAV_ON_PLAN_M
            and ev.camera_vs_plan_m is not None and ev.camera_vs_plan_m < nav_plan)


def _force_ramp(ev: Evidence, failed: Sequence[str] | None) -> bool:
    """Whether, after a NIS crossing over more than ``STEP_SPAN`` updates (a ramp), the NIS
    still fails with the nav on its plan (``NAV_ON_PLAN_M``): an unmodelled force pulling the
    truth off the plan the nav holds.  Its innovations grow with the truth's drift, update
    after update, while the nav lags the truth it steers; a sensor's bias and the truth's
    jump put their whole innovation in the first update, and a biased nav walks off its
    plan (0.25-0.5 m in the first window).  On the sequential archives of the hard, beyond,
    paper and identify campaigns, 76 of 84 thruster leaks the NIS scan declared crossed
    over 4-32 updates and 75 of 75 nav biases and state disturbances over one."""
    return "nis" in (failed or []) and (ev.nav_vs_plan_m or 0.0) < NAV_ON_PLAN_M


NAV_ON_PLAN_M = 0.1
"""A nav estimate this close to its plan (median over the window), m, is on it: within the
nominal spread of a nav steering its spacecraft along the plan, and far below the 0.25-0.5 m
a biased nav walks off the plan in the first window of its step."""


def _truth_not_followed(ev: Evidence, tol: Tolerances) -> bool:
    """Whether the truth has left a nav still on its plan (``NAV_ON_PLAN_M``): the camera
    located more than half the position tolerance off the nav.  With the NIS test failing this
    is an unmodelled force's first seconds (a leak, a state disturbance), before the nav has
    followed the truth; a settled nav bias shows the same geometry, but its NIS passes."""
    return ((ev.nav_vs_plan_m or 0.0) < NAV_ON_PLAN_M
            and (ev.camera_vs_nav_m or 0.0) > tol.position_m / 2.0)


def _nav_left_camera(ev: Evidence) -> bool:
    """Whether the located camera is on the plan within ``SE_MARGIN`` standard errors of the
    fixes' median (``Evidence.camera_se_m``) and off the nav beyond them: the nav has left a
    spacecraft that stayed.  A leak's truth leads its nav off the plan, so its camera is the
    farther from the plan; a biased nav walks off ahead of the truth it steers.  A noisy
    camera's fixes place it far from a plan it holds (space campaign, fault-0099: a 3.75 m
    nav bias, the nav 1.16 m off the plan, the camera 0.42 m off it and 1.30 m off the nav,
    0.36 m standard error), which the fixed ``position_tol_m`` / 2 does not allow for."""
    if ev.camera_vs_plan_m is None or ev.camera_se_m is None:
        return False
    return ev.camera_vs_plan_m <= SE_MARGIN * ev.camera_se_m < (ev.camera_vs_nav_m or 0.0)


def _beyond_fixes(ev: Evidence, distance_m: float) -> bool:
    """Whether a distance of the located camera (m) is beyond ``SE_MARGIN`` standard errors of
    the fixes' median (``Evidence.camera_se_m``)."""
    return distance_m > SE_MARGIN * (ev.camera_se_m or 0.0)


def _alignment(ev: Evidence) -> float | None:
    """``Evidence.offset_alignment``, where the located camera's offset from the plan exceeds
    the standard error of its fixes (a camera on the plan, within its noise, has no
    direction)."""
    if (ev.camera_vs_plan_m is not None and ev.camera_se_m is not None
            and ev.camera_vs_plan_m <= ev.camera_se_m):
        return None
    return ev.offset_alignment


def located_cameras(twin: TwinModel, images: Sequence[Observation]
                    ) -> list[tuple[int, CameraFix]]:
    """The camera located from each image that allows it (:func:`locate_camera`, the images
    fitted together: ``ground.fdir.trilateration.least_squares_each``), by image index; none
    when fewer than ``MIN_FIXES`` images do."""
    if not images:
        return []
    if any(len(poi) != len(prec) for poi, prec in images):
        raise ValueError("an image's POI indices and precisions differ in number")
    seen = np.concatenate([poi for poi, _ in images])
    kp = twin.camera.k * np.concatenate([prec for _, prec in images])
    starts = np.cumsum([0] + [len(poi) for poi, _ in images], dtype=np.int64)
    fixes = [camera_fix(coef, twin.radius_m, twin.noise_frac)
             for coef in least_squares_each(twin.pois.pos, seen, kp, starts, MIN_POIS)]
    located = [(i, f) for i, f in enumerate(fixes) if f is not None]
    return located if len(located) >= MIN_FIXES else []


def pose_evidence(located: list[tuple[int, CameraFix]], pose: WindowPose, radius_m: float,
                  dv_rate: float | None) -> Evidence:
    """The cheap part of a window's identification evidence, judged every window so that its
    nominal spread is in the archive: the located cameras (``located``), the reported nav and
    attitude against the plan (``pose``: the window test's statistics, ``gnc/window_test.py``).
    ``radius_m``: the target's."""
    planned, nav = pose.planned, pose.nav
    betas = np.array([f.beta for _, f in located])
    beta, beta_se = (float(np.median(betas)), median_se(betas)) if located else (None, None)
    cam_nav = align = cam_plan = None
    camera_se: tuple[float | None, float | None] = (None, None)
    if located:
        off_plan = np.array([f.position_m - planned[i] for i, f in located])
        cam_plan = float(np.linalg.norm(np.median(off_plan, axis=0)))
        camera_se = _camera_se(off_plan, planned, radius_m)
    if nav is not None and located:
        d = np.array([f.position_m - nav[i] for i, f in located])
        cam_nav = float(np.linalg.norm(np.median(d, axis=0)))
        align = offset_alignment(np.array([f.position_m for _, f in located]),
                                 nav[[i for i, _ in located]], planned[[i for i, _ in located]])
    return Evidence(beta_hat=beta, camera_vs_nav_m=cam_nav, nav_vs_plan_m=pose.nav_vs_plan_m,
                    pointing_error_deg=pose.pointing_error_deg, dv_rate_mps2=dv_rate,
                    offset_alignment=align,
                    camera_vs_plan_m=cam_plan, beta_se=beta_se, camera_se_m=camera_se[0],
                    camera_se_deg=camera_se[1])


def gap_evidence(ev: Evidence, twin: TwinModel, images: Sequence[Observation],
                 located: list[tuple[int, CameraFix]], nav: np.ndarray | None,
                 attitude: np.ndarray | None, psi: np.ndarray, phi: np.ndarray,
                 gap: tuple[float, float], fit_boresight: bool) -> Evidence:
    """``ev`` completed for a window that exceeded its threshold (``gap`` = (ΔH_i,
    ΔH_i^pred)): the twin at the reported pose and the seen-set overlap, and with
    ``fit_boresight`` (a window that must name a class) the boresight the seen POIs show."""
    explained = explained_loc = overlap = offset = None
    if nav is not None and attitude is not None:
        explained, explained_loc, overlap = _gap_evidence(twin, images, nav, attitude, located,
                                                          psi, phi, gap)
    if fit_boresight and attitude is not None and located:
        offset = camera_offset_deg(twin, images, attitude, located)
    return replace(ev, seen_overlap=overlap, explained_reported=explained,
                   explained_located=explained_loc, camera_offset_deg=offset)


def _camera_se(off_plan: np.ndarray, planned: np.ndarray, radius_m: float
               ) -> tuple[float, float]:
    """The standard error of the located camera's median offset from the plan (K, 3; offsets,
    not positions: the camera moves along its orbit during the window), m, and the angle it
    subtends from the target's near surface (the plan's median range less the radius), deg."""
    se = math.hypot(*(median_se(off_plan[:, j]) for j in range(3)))
    near = float(np.median(np.linalg.norm(planned, axis=1))) - radius_m
    return se, math.degrees(math.atan2(se, max(near, radius_m)))


NORMAL_MAD = 0.6744897501960817
"""The median absolute deviation of a standard normal, Φ⁻¹(3/4): MAD / this estimates σ (the
constant and division of ``scipy.stats.median_abs_deviation(scale="normal")``)."""


def median_se(values: npt.ArrayLike) -> float:
    """Standard error of the median of ``values``, from their spread: √(π/2) σ / √n, with σ
    the median absolute deviation scaled to a normal's (robust to the odd wild fix).  The MAD
    is scipy's ``median_abs_deviation(scale="normal")`` written out (the same operations, so
    the same bits, tested): scipy's call costs ~0.4 ms, four of them a window."""
    v = np.asarray(values, dtype=float)
    sigma = float(np.median(np.abs(v - np.median(v)))) / NORMAL_MAD
    return math.sqrt(math.pi / 2.0) * sigma / math.sqrt(len(v))


OFFSET_IMAGES = 5
"""Located images of a window whose boresight is fitted (evenly spread)."""


def camera_offset_deg(twin: TwinModel, images: Sequence[Observation], attitude: np.ndarray,
                      located: list[tuple[int, CameraFix]]) -> float | None:
    """Median over up to ``OFFSET_IMAGES`` located images of the angle between the reported
    boresight and the one the seen POIs show (``ground/fdir/boresight.py``), deg."""
    k = sample_stride(len(located), OFFSET_IMAGES)
    angles = [boresight_offset(f.position_m, attitude[i, :3], images[i][0], twin.poi_pos,
                               twin.poi_normal, twin.camera) for i, f in located[::k]]
    valid = [a for a in angles if a is not None]
    return math.degrees(float(np.median(valid))) if valid else None


MIN_OFFSET_M = 0.05
"""An offset from the plan shorter than this has no direction worth comparing, m."""
SAME_WAY = 0.5
"""``offset_alignment`` above this: camera and nav are off the plan the same way."""


def offset_alignment(camera: np.ndarray, nav: np.ndarray, planned: np.ndarray) -> float | None:
    """Cosine between the median offsets from the plan of the located camera positions and of
    the nav estimates at the same images (K, 3 each); None when either is under
    ``MIN_OFFSET_M``."""
    a = np.median(camera - planned, axis=0)
    b = np.median(nav - planned, axis=0)
    na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    if na < MIN_OFFSET_M or nb < MIN_OFFSET_M:
        return None
    return float(a @ b) / (na * nb)


def _gap_evidence(twin: TwinModel, images: Sequence[Observation], nav: np.ndarray,
                  attitude: np.ndarray, located: list[tuple[int, CameraFix]], psi: np.ndarray,
                  phi: np.ndarray, gap: tuple[float, float]
                  ) -> tuple[float | None, float | None, float | None]:
    """The gradient test (the twin re-run at the reported pose, and with the located camera
    positions) and the seen-set overlap of an exceeded window."""
    bore = attitude[:, :3] / np.linalg.norm(attitude[:, :3], axis=1, keepdims=True)
    explained = explained_fraction(gap[0], gap[1], twin.predicted(nav, bore, psi, phi))
    where = nav.copy()
    for i, f in located:
        where[i] = f.position_m
    explained_loc = explained_fraction(gap[0], gap[1], twin.predicted(where, bore, psi, phi))
    k = sample_stride(len(images))
    vis = visibility(nav[::k], bore[::k], twin.poi_pos, twin.poi_normal, twin.camera)
    ratios = [seen_overlap(poi, np.flatnonzero(v))
              for (poi, _), v in zip(images[::k], vis, strict=True)]
    valid = [r for r in ratios if r is not None]
    return explained, explained_loc, float(np.median(valid)) if valid else None
