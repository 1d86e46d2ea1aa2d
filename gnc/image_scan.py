"""The image scan of the sequential test (issue 41; docs/fdir.md, "The sequential test"), the
one the ground's FDIR and the neighbours' judge aboard both run: each observer's images scored
as they come, against the nominal twin at its plan (Eq. 9 image by image), and the scan over
the newest (``gnc/sequential_test.py``) crossing its threshold c.

The ratio's nominal distribution comes from the hardware model once per observer and window
(``gnc.window_test.pose_ratio_model``), drawn on the plan's poses over the whole window (the
imaged ones: ``gnc.hardware_threshold.imaged``) with the pose spreads the observer reports;
an image's σ_b is the larger of the spreads at the two drawn poses about it.  Whoever feeds it
holds ψ at the window's start, as the window test does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from gnc.fdi_metric import Direction
from gnc.hardware_threshold import RatioModel, imaged, pose_spreads_at
from gnc.sequential_test import ImageEvidence, ScanBuffer, ScanResult, image_evidence
from gnc.twin import TwinModel, delta_h
from gnc.window_test import WindowPose, WindowTestSettings, pose_ratio_model
from interfaces.contracts.timing import TIME_TOL_S

FloatArray = np.ndarray
Seen = list[tuple[np.ndarray, np.ndarray]]
"""An image's observations: the POIs (int) and their measured precisions."""


@dataclass(frozen=True)
class Crossing:
    """A scan crossing its threshold: at an image (the information scan: the image's time,
    s; the span's mean relative shift and the shift it had to exceed), at a nav update (the
    NIS scan, ``test = "nis"``: the update's time; the span's mean NIS per degree of freedom
    and the mean it had to exceed), or at the last of ``POINTING_RUN`` images in a row whose
    reported pointing error exceeds the tolerance (``test = "pointing"``: their median error
    and the tolerance, deg); ``since_s``, the time of the span's first image or update (s;
    None: the crossing's own)."""

    image_t_s: float
    scan: ScanResult
    shift: float
    limit: float
    test: Literal["information", "nis", "pointing"] = "information"
    since_s: float | None = None

    @property
    def change_s(self) -> float:
        """When the change began, as the scan estimates it (s): the start of the span whose
        statistic was the largest, the change point the dyadic spans allow (the span that
        matches a sustained change is within a factor of two of one of them)."""
        return self.image_t_s if self.since_s is None else self.since_s

    @property
    def direction(self) -> Direction | None:
        """Table 3's direction: the gain below the prediction is degraded (None: the NIS
        scan and the pointing run, which judge no gain)."""
        if self.test != "information":
            return None
        return "degraded" if self.scan.signed < 0.0 else "improved"


@dataclass
class _WindowStats:
    """What one observer's scored images of the window starting at ``a`` (s) showed: the
    largest scan statistic, and the sum of their nominal variances over their number."""

    a: float
    z_max: float = 0.0
    var_sum: float = 0.0
    images: int = 0
    latest: tuple[float, float] = (-math.inf, 0.0)
    """the newest image's time (s) and the scan statistic at it"""

    def add(self, t: float, z: float, sigma_e: float, sigma_b: float) -> None:
        self.latest = (t, z)
        self.z_max = max(self.z_max, z)
        self.var_sum += sigma_e * sigma_e + sigma_b * sigma_b
        self.images += 1


def step_false_alarm(per_hour: float, tests: int, rate_hz: float) -> float:
    """A scan's false-alarm probability per image (or nav update): its share, one of
    ``tests`` fused tests, of the budget ``per_hour`` false alarms per observer-hour over the
    steps of an hour (one every ω_mid period, ``rate_hz``)."""
    return min(per_hour / max(tests, 1) / (3600.0 * rate_hz), 0.5)


POINTING_RUN = 5
"""Scored images in a row whose reported pointing error exceeds ``pointing_tol_deg`` that
declare a pointing fault at once (the window test's pointing test, image by image; with
``fdir.fuse_guidance``).  A persistence rule on a tolerance, not a model: five seconds at
1 Hz, against the window's median over half its 30 images.  An image is scored only
``fdir.settle_s`` after its slew ended (a slew's overshoot exceeds the tolerance for up to
25 s after it); then the reported error of a healthy attitude loop stays within a tenth of
the tolerance."""


def _pointing_crossing(scan: ScanBuffer, run_rad: np.ndarray, tol_rad: float) -> Crossing:
    """The pointing run's crossing at the scan's newest image: the run's median reported
    error against the tolerance (deg), their ratio as the statistic, its change at the run's
    first image."""
    error, tol = math.degrees(float(np.median(run_rad))), math.degrees(tol_rad)
    run = scan.beyond_run
    return Crossing(scan.times[-1], ScanResult(error / tol, error / tol, run), error, tol,
                    "pointing", scan.times[-run])


class ImageScans:
    """Every observer's image scan against the nominal ``twin`` at threshold ``c``, its
    ratio models drawn with the generator seeded by ``rng_key`` + (observer, window start,
    2); ``noise_var``: the camera's clipped noise factor's variance; ``image_period_s``: the
    ω_mid period, s."""

    def __init__(self, settings: WindowTestSettings, twin: TwinModel, noise_var: float,
                 c: float, image_period_s: float, rng_key: tuple[int, ...]) -> None:
        self.settings = settings
        self.twin = twin
        self.noise_var = noise_var
        self.c = c
        self.image_period_s = image_period_s
        self.rng_key = rng_key
        self._scans: dict[int, ScanBuffer] = {}
        self._models: dict[int, tuple[float, RatioModel | None, np.ndarray, bool]] = {}
        """each observer's window start (s), its ratio model, the times of its poses and
        whether they are the plan's over the whole window"""
        self._stats: dict[int, _WindowStats] = {}
        """each observer's scored images of its latest window"""

    def image_fields(self, observer: int, a: float) -> dict[str, float]:
        """The scan's record of ``observer``'s window starting at ``a`` (s), the latest it
        scored, as ``FdirWindow``'s ``scan_z_max``, ``scan_threshold`` and ``image_sigma``;
        empty when no image of it was scored."""
        stats = self._stats.get(observer)
        if stats is None or abs(stats.a - a) > TIME_TOL_S or not stats.images:
            return {}
        return {"scan_z_max": stats.z_max, "scan_threshold": self.c,
                "image_sigma": math.sqrt(stats.var_sum / stats.images)}

    def latest(self, observer: int) -> tuple[float, float] | None:
        """``observer``'s newest scored image: its time (s) and the scan statistic
        max_n |Z_n| at it; None: none scored."""
        stats = self._stats.get(observer)
        return stats.latest if stats is not None and stats.images else None

    def last_scored_s(self, observer: int) -> float:
        """The time of ``observer``'s last image looked at (scored or passed over), s."""
        scan = self._scans.get(observer)
        return scan.last_t if scan is not None else -math.inf

    def evidence_since(self, observer: int, a: float) -> bool:
        """Whether ``observer`` has an image scored at or after ``a`` (s): its evidence
        counts in the window starting there (the common-mode rule, Eq. 6)."""
        scan = self._scans.get(observer)
        return scan is not None and scan.scored_t >= a - TIME_TOL_S

    def passed(self, observer: int, t: float) -> None:
        """``observer``'s images up to ``t`` (s) pass unscored (none can be judged: a slew,
        no plan known)."""
        scan = self._scans.setdefault(observer, ScanBuffer())
        scan.last_t = max(scan.last_t, t)

    def reset(self, observer: int) -> None:
        """``observer``'s scan starts afresh (its crossing decided), keeping the times of its
        last images."""
        old = self._scans.get(observer, ScanBuffer())
        self._scans[observer] = ScanBuffer(last_t=old.last_t, scored_t=old.scored_t)

    def plan_times(self, a: float, b: float) -> np.ndarray:
        """The times (s) of window [a, b)'s images the ratio model draws on: one every ω_mid
        period, those the pose draws image (``gnc.hardware_threshold.imaged``)."""
        return imaged(np.arange(a, b - TIME_TOL_S, self.image_period_s))

    def modelled(self, observer: int, a: float) -> bool:
        """Whether ``observer``'s ratio model of the window starting at ``a`` (s) is drawn
        already on the plan over the whole window (its plan is then not needed)."""
        held = self._models.get(observer)
        return held is not None and abs(held[0] - a) < TIME_TOL_S and held[3]

    def score_images(self, observer: int, window: tuple[float, float], times: np.ndarray,
                     seen: Seen, pose: WindowPose, psi: np.ndarray, phi: np.ndarray,
                     plan: np.ndarray | None) -> Crossing | None:
        """Score ``observer``'s images of ``window`` [a, b) (s) not yet scored, taken at
        ``times`` (time order) with the observations ``seen``, at the pose ``pose`` reports:
        the first at which the scan crosses c, or None.  ψ, φ held at a; ``plan``: the
        planned positions (K, 3) at :meth:`plan_times` (None: not known there), where the
        ratio model is drawn."""
        scan = self._scans.setdefault(observer, ScanBuffer())
        model, model_times = self._model(observer, window, times, pose, psi, phi, plan)
        if model is None:
            scan.last_t = float(times[-1])
            return None
        prec = self.twin.precision(pose.planned, pose.boresights())
        gains = np.array([delta_h(psi[poi], phi[poi], p) for poi, p in seen])
        evidence = image_evidence(gains, prec * (phi * psi), model.mean, self.noise_var)
        at = times[evidence.kept]
        pointing = (np.asarray(pose.pointing_error_rad)[evidence.kept]
                    if self.settings.fuse_pose and pose.pointing_error_rad is not None
                    else None)
        crossing = self._push(observer, window[0], at, evidence,
                              pose_spreads_at(model, model_times, at), pointing)
        if crossing is None:
            scan.last_t = float(times[-1])
        return crossing

    def _push(self, observer: int, a: float, at: np.ndarray, evidence: ImageEvidence,
              sigma_b: np.ndarray, pointing_rad: np.ndarray | None) -> Crossing | None:
        """The images at ``at`` (s) pushed onto the observer's scan one by one until the scan
        crosses c or ``POINTING_RUN`` images in a row report their pointing error
        (``pointing_rad``; None: not judged) beyond the tolerance: that image's crossing;
        each counted in the record of the window starting at ``a`` (s)."""
        tol = self.settings.pointing_tol_rad
        scan = self._scans[observer]
        stats = self._stats.get(observer)
        if stats is None or abs(stats.a - a) > TIME_TOL_S:
            stats = self._stats[observer] = _WindowStats(a)
        for i, (t, rk, ek, bk) in enumerate(zip(at, evidence.residuals, evidence.sigma_e,
                                                sigma_b, strict=True)):
            scan.push(float(rk), float(ek), float(bk), float(t),
                      pointing_rad is not None and bool(pointing_rad[i] > tol))
            result = scan.scan()
            stats.add(float(t), result.z if result is not None else 0.0, float(ek), float(bk))
            if result is not None and result.z > self.c:
                shift = float(np.mean(scan.r[-result.span:]))
                return Crossing(float(t), result, shift, self.c * abs(shift) / result.z,
                                since_s=scan.times[-result.span])
            if pointing_rad is not None and scan.beyond_run >= POINTING_RUN:
                run = pointing_rad[max(0, i + 1 - POINTING_RUN):i + 1]  # of this call's
                return _pointing_crossing(scan, run, tol)
        return None


    def _model(self, observer: int, window: tuple[float, float], times: np.ndarray,
               pose: WindowPose, psi: np.ndarray, phi: np.ndarray, plan: np.ndarray | None
               ) -> tuple[RatioModel | None, np.ndarray]:
        """The ratio model of the observer's window and the times of the poses it imaged:
        drawn once a window, on the planned poses at :meth:`plan_times`, with the pose
        spreads the observer reports there.  Where the plan is not known over the whole
        window (a transfer planned after the window began), on the first scored images, and
        drawn again on the plan once it is known: a model of the poses before a departure
        does not hold for the transfer after it (identify campaign, late-thruster-0002: a
        crossing at z = 6.1 on a healthy observer 13 s into a transfer, against a model of
        station-keeping, 0.85% per image where the transfer's window spread 5.4%)."""
        held = self._models.get(observer)
        if held is not None and abs(held[0] - window[0]) < TIME_TOL_S and (
                held[3] or plan is None):
            return held[1], held[2]
        rng = np.random.default_rng([*self.rng_key, observer, int(round(window[0])), 2])
        drawn_at = imaged(self.plan_times(*window) if plan is not None else times)
        model = pose_ratio_model(pose, self.twin, psi, phi, None, self.settings, rng, plan)
        self._models[observer] = (window[0], model, drawn_at, plan is not None)
        return model, drawn_at
