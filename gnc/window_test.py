"""The window test: one observer's FDI window judged against its plan (docs/fdir.md, "Detection
and isolation"), the one test the ground's FDIR (``ground/fdir/information.py``) and the
neighbours' judge (``fsw/lib/neighbour_judge.py``) both run, fed by arrays -- what the
observer's images saw, where its plan puts it and what it reports of its pose at the images'
times (``WindowPose``) -- with the settings both read from the scenario
(``WindowTestSettings``):

* the information test (Sec. III.B-E): H_m,i = |1 − ΔH_i/ΔH_i^pred| (Eq. 9) of the images'
  ΔH_i against the twin's ΔH_i^pred at the plan, the camera on the reported aim point
  (:func:`information`), against τ_i: the hardware model's quantile for the window's
  false-alarm share (``gnc/hardware_threshold.py``, in the place of Eq. 11-12's sampled τ),
  raised to the floor guard ``fdir.floor`` (:func:`hardware_threshold`);
* the pose tests fused with it (``fdir.fuse_guidance``, :func:`pose_tests`): the median
  distance of the reported nav from the plan, the median reported pointing error and, where
  the judge has the observer's guidance reports (the ground), the Δv it commands per second
  while holding its PRO, each against its tolerance.

A window fails when any of its tests fails (:func:`failed_tests`); it is decided when the
information test could decide or any test failed (:func:`exceeded`).  The ground adds Eq.
11-12's sampled τ and the nav's NIS test (``ground/fdir/threshold.py``,
``ground/fdir/consistency.py``).  Pure functions and frozen dataclasses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt

from gnc.fdi_metric import Direction, direction, metric
from gnc.hardware_threshold import RatioModel, position_sigma, ratio_model, window_false_alarm
from gnc.twin import TwinModel, aimed_boresights, centre_boresights, delta_h
from interfaces.contracts.scenario import Scenario

FloatArray = npt.NDArray[np.float64]

Observation = tuple[npt.NDArray[np.int_], FloatArray]
"""One image's observations: POI indices and their precisions σ⁻¹."""


@dataclass(frozen=True)
class WindowTestSettings:
    """What the window test takes from the scenario: ``[fdir]``, ``[camera] noise_frac`` and
    the window's length ``rates.fdi_period_s``.

    Attributes:
        settle_s: time in track after a slew before an image is judged, s.
        track_sigma_m: station-keeping accuracy holding a PRO, 1σ per axis, m.
        transfer_sigma_m: tracking accuracy on a transfer, 1σ per axis, m.
        pointing_jitter_rad: attitude loop tracking error, 1σ per axis, rad.
        noise_frac: ν, 1σ multiplicative noise of each measured precision.
        model_samples: pose draws of the hardware model per window.
        floor: the floor guard under τ.
        position_tol_m: the plan test's bound on the nav's distance from the plan, m.
        pointing_tol_deg: the pointing test's bound on the reported pointing error, deg.
        dv_rate_tol_mps2: the Δv-rate test's bound while holding a PRO, m/s².
        fuse_pose: whether the pose tests are fused with the information test.
        false_alarms_per_hour: the false-alarm budget per observer-hour.
        window_s: the FDI window's length, s.
        persistence: failed windows in a row that declare a fault.
    """

    settle_s: float
    track_sigma_m: float
    transfer_sigma_m: float
    pointing_jitter_rad: float
    noise_frac: float
    model_samples: int
    floor: float
    position_tol_m: float
    pointing_tol_deg: float
    dv_rate_tol_mps2: float
    fuse_pose: bool
    false_alarms_per_hour: float
    window_s: float
    persistence: int

    @classmethod
    def of(cls, scenario: Scenario) -> WindowTestSettings:
        cfg = scenario.fdir
        return cls(cfg.settle_s, cfg.track_sigma_m, cfg.transfer_sigma_m,
                   math.radians(cfg.pointing_jitter_deg), scenario.camera.noise_frac,
                   cfg.model_samples, cfg.floor, cfg.position_tol_m, cfg.pointing_tol_deg,
                   cfg.dv_rate_tol_mps2, cfg.fuse_guidance, cfg.false_alarms_per_observer_hour,
                   scenario.rates.fdi_period_s, cfg.persistence)

    @property
    def pointing_tol_rad(self) -> float:
        return math.radians(self.pointing_tol_deg)

    def false_alarm(self, tests: int = 1) -> float:
        """The false-alarm probability of each of ``tests`` statistical tests fused per window
        (``gnc.hardware_threshold.window_false_alarm``): aboard, the information test alone
        (with the image scan, ``fdir.detector = "sequential"``); on the ground, the information
        and NIS tests with ``fdir.fuse_nis``, and the scans."""
        return window_false_alarm(self.false_alarms_per_hour, self.window_s, self.persistence,
                                  tests)


@dataclass(frozen=True, eq=False)
class WindowPose:
    """Where the plan puts the observer at the judged images' times (K rows) and what it
    reports of its pose there; None where it reports nothing (stale or missing telemetry).

    Attributes:
        planned: the plan's positions (K, 3), LVLH m.
        aims: the aim points its camera policy reports (K, 3), LVLH m (None: the target
            centre).
        nav: its nav estimate's positions (K, 3), LVLH m.
        nav_sigma_m: its nav's position 1σ per axis (K values), m.
        pointing_error_rad: the pointing error its attitude estimate reports (K,), rad.
        knowledge_rad: its attitude knowledge 1σ (K,), rad.
        moving: whether any image falls on a transfer.
    """

    planned: FloatArray
    aims: FloatArray | None
    nav: FloatArray | None
    nav_sigma_m: FloatArray | None
    pointing_error_rad: FloatArray | None
    knowledge_rad: FloatArray | None
    moving: bool = False

    def boresights(self) -> FloatArray:
        """The twin's pointing (K, 3): from each planned position to the reported aim point
        (the target centre without one).  A pointing or camera fault leaves the aim as
        intended, so it still shows against this prediction."""
        if self.aims is None:
            return centre_boresights(self.planned)
        return aimed_boresights(self.aims, self.planned)

    @cached_property
    def nav_vs_plan_m(self) -> float | None:
        """The median distance of the reported nav from the plan, m."""
        if self.nav is None:
            return None
        return float(np.median(np.linalg.norm(self.nav - self.planned, axis=1)))

    @cached_property
    def pointing_error_deg(self) -> float | None:
        """The median pointing error the attitude estimate reports, deg."""
        if self.pointing_error_rad is None:
            return None
        return math.degrees(float(np.median(self.pointing_error_rad)))

    def position_sigma(self, cfg: WindowTestSettings) -> float:
        """The truth's 1σ per axis about the plan (``gnc.hardware_threshold.position_sigma``):
        the station-keeping spec (on a transfer, its tracking), the nav's mean reported 1σ
        and its reported offsets from the plan up to the plan test's tolerance."""
        spec = cfg.transfer_sigma_m if self.moving else cfg.track_sigma_m
        nav_sigma = float(np.mean(self.nav_sigma_m)) if self.nav_sigma_m is not None else 0.0
        offsets = None if self.nav is None else self.nav - self.planned
        return position_sigma(spec, nav_sigma, offsets, cfg.position_tol_m)

    def pointing_sigma(self, cfg: WindowTestSettings) -> float:
        """The boresight's 1σ per axis about the aim: the loop's jitter, the mean reported
        attitude knowledge and the median reported pointing error, up to the pointing test's
        tolerance (beyond it the pointing test decides).  The first window after the initial
        acquisition still holds the loop's transient, which the jitter alone does not cover."""
        knowledge = (float(np.mean(self.knowledge_rad)) if self.knowledge_rad is not None
                     else 0.0)
        tracking = min(float(np.median(self.pointing_error_rad))
                       if self.pointing_error_rad is not None else 0.0, cfg.pointing_tol_rad)
        return math.hypot(cfg.pointing_jitter_rad, knowledge, tracking)


@dataclass(frozen=True, eq=False)
class Information:
    """The window's information: ΔH_i of its images and the twin's ΔH_i^pred with ψ held at
    the window start, H_m,i (Eq. 9; None: degenerate prediction), the direction (Table 3),
    and the twin's predicted precisions (K, M)."""

    dh: float
    dh_pred: float
    metric: float | None
    direction: Direction | None
    prec: FloatArray


def information(seen: Sequence[Observation], pose: WindowPose, psi: FloatArray,
                phi: FloatArray, twin: TwinModel, h_prev: float = 0.0) -> Information:
    """ΔH_i = Σ φψσ⁻¹ over each image's observations ``seen`` and ΔH_i^pred of the nominal
    twin at ``pose`` (β = 1), ψ and φ of the judge's map at the window start; ``h_prev``: the
    observer's H_i there, the scale of Eq. 9's degeneracy test (0: none)."""
    dh = sum(delta_h(psi[poi], phi[poi], prec) for poi, prec in seen)
    prec = twin.precision(pose.planned, pose.boresights())
    dh_pred = delta_h(psi, phi, prec)
    return Information(dh, dh_pred, metric(dh, dh_pred, h_prev),
                       direction(dh, dh_pred, h_prev), prec)


def floor_guard(tau: float, floor: float) -> tuple[float, bool]:
    """τ raised to the floor guard ``floor`` where it is below, and whether the floor set
    it."""
    return (floor, True) if floor > tau else (tau, False)


@dataclass(frozen=True)
class HardwareThreshold:
    """The hardware model's threshold of one window: the ratio's nominal distribution
    (``model``), its quantile τ with P(|1 − x| > τ) = q (``quantile``), and the τ in force,
    raised to the floor guard (``tau``, ``floored``: the floor set it)."""

    model: RatioModel
    quantile: float
    tau: float
    floored: bool


def hardware_threshold(pose: WindowPose, twin: TwinModel, psi: FloatArray, phi: FloatArray,
                       prec: FloatArray, cfg: WindowTestSettings, q: float,
                       rng: np.random.Generator) -> HardwareThreshold | None:
    """τ_i of the window from the hardware (Sec. III.E; Eq. 11-12's place): the ratio model
    (``gnc.hardware_threshold.ratio_model``, ``cfg.model_samples`` pose draws from ``rng``)
    with the pose's spreads, its quantile for the false-alarm probability ``q``, raised to
    the floor guard; ``prec``: the twin's predicted precisions.  None when the prediction
    holds no information (no threshold, no decision)."""
    model = pose_ratio_model(pose, twin, psi, phi, prec, cfg, rng)
    if model is None:
        return None
    quantile = model.threshold(q)
    return HardwareThreshold(model, quantile, *floor_guard(quantile, cfg.floor))


def pose_ratio_model(pose: WindowPose, twin: TwinModel, psi: FloatArray, phi: FloatArray,
                     prec: FloatArray | None, cfg: WindowTestSettings, rng: np.random.Generator,
                     positions: FloatArray | None = None) -> RatioModel | None:
    """The ratio's nominal distribution for the images of ``pose``
    (``gnc.hardware_threshold.ratio_model``): the pose's spreads as the observer reports them
    (``WindowPose.position_sigma``, ``pointing_sigma``), ``cfg.model_samples`` pose draws from
    ``rng``; ``prec``: the twin's predicted precisions (None: computed).  ``positions``: other
    planned poses (K, 3) to draw on instead of the images' (the plan over the whole window),
    aimed as the last image was.  None when the prediction holds no information."""
    if positions is None:
        positions, aims = pose.planned, pose.aims
    else:
        aims = None if pose.aims is None else np.repeat(pose.aims[-1:], len(positions), axis=0)
    aims = aims if aims is not None else np.zeros_like(positions)
    return ratio_model(twin, positions, aims, psi, phi, pose.position_sigma(cfg),
                       pose.pointing_sigma(cfg), cfg.noise_frac, cfg.model_samples, rng, prec)


def pose_tests(pose: WindowPose, dv_rate_mps2: float | None, cfg: WindowTestSettings
               ) -> list[str]:
    """The pose tests the window fails (none unless ``cfg.fuse_pose``), by the names a
    window's verdict gives them (``interfaces.contracts.messages.WINDOW_TESTS``): ``plan``
    when the reported nav's median distance from the plan exceeds ``position_tol_m``,
    ``pointing`` when the median reported pointing error exceeds ``pointing_tol_deg``,
    ``dv_rate`` when the Δv commanded per second while holding the PRO (``dv_rate_mps2``;
    None: not known) exceeds ``dv_rate_tol_mps2``.  What is not reported does not fail."""
    if not cfg.fuse_pose:
        return []
    failed = []
    if (pose.nav_vs_plan_m or 0.0) > cfg.position_tol_m:
        failed.append("plan")
    if (pose.pointing_error_deg or 0.0) > cfg.pointing_tol_deg:
        failed.append("pointing")
    if (dv_rate_mps2 or 0.0) > cfg.dv_rate_tol_mps2:
        failed.append("dv_rate")
    return failed


def failed_tests(info: Information, tau: float | None, pose: WindowPose,
                 dv_rate_mps2: float | None, cfg: WindowTestSettings) -> list[str]:
    """The window's failed tests: ``information`` when H_m,i exceeds the threshold in force
    ``tau`` (Eq. 9 against τ_i), then the pose tests (:func:`pose_tests`)."""
    failed = [] if info.metric is None or tau is None or info.metric <= tau else ["information"]
    return failed + pose_tests(pose, dv_rate_mps2, cfg)


def exceeded(failed: Sequence[str], decided: bool) -> bool | None:
    """The window's verdict: whether any test failed, or None when none failed and the
    information test could not decide (``decided``: a metric and a threshold)."""
    return bool(failed) if failed or decided else None
