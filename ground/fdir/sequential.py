"""The FDIR pipeline's sequential test (issue 41; docs/fdir.md, "The sequential test"): with
``fdir.detector = "sequential"``, each observer's images are scored as they reach the ground,
each against the nominal twin at the plan (Eq. 9 image by image), and the scan over the
newest images (``gnc/sequential_test.py``) declares the moment it crosses its threshold,
instead of waiting for the window's end.

The images of window [a, b) are scored once the ground's map is settled at a (window k − 1
judged), with ψ held at a as the window test holds it.  The ratio's nominal distribution comes
from the hardware model once per observer and window, on the images then in (their planned
poses and the pose spreads the observer reports).  An observer whose fault is declared is not
scored until its episode ends; its scan then starts afresh.

With ``fdir.fuse_nis``, the nav's NIS is scanned the same way, update by update
(``gnc.sequential_test.chi2_scan``): the window's NIS test (Σ NIS over a window against
χ²(6N)) is its span of a window; its shorter spans declare an orbit actuator fault, whose
innovations grow within seconds, before the window ends.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from gnc.fdi_metric import Direction
from gnc.hardware_threshold import RatioModel, clipped_noise_moments, imaged, pose_spreads_at
from gnc.sequential_test import (
    SCAN_LENGTHS,
    ImageEvidence,
    ScanBuffer,
    ScanResult,
    chi2_scan,
    chi2_span_limit,
    image_evidence,
)
from gnc.sequential_test import scan_threshold as scan_threshold_for
from gnc.twin import TwinModel, delta_h
from gnc.window_test import WindowTestSettings, pose_ratio_model
from ground.fdir.baselines import NIS_DOF
from ground.fdir.window import WindowContext
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S


@dataclass(frozen=True)
class Crossing:
    """A scan crossing its threshold: at an image (the information scan: the image's time,
    s; the span's mean relative shift and the shift it had to exceed) or at a nav update (the
    NIS scan, ``test = "nis"``: the update's time; the span's mean NIS per degree of freedom
    and the mean it had to exceed)."""

    image_t_s: float
    scan: ScanResult
    shift: float
    limit: float
    test: Literal["information", "nis"] = "information"

    @property
    def direction(self) -> Direction | None:
        """Table 3's direction: the gain below the prediction is degraded (None: the NIS
        scan, which judges no gain)."""
        if self.test == "nis":
            return None
        return "degraded" if self.scan.signed < 0.0 else "improved"


@dataclass
class _NisScan:
    """One observer's newest NIS values (oldest first, at most the longest span) and the time
    of the last update looked at."""

    values: list[float] = field(default_factory=list)
    last_t: float = -math.inf
    window: tuple[float, float] | None = None
    """the start of the window its last updates were scored in (s) and their largest z"""


@dataclass
class _WindowStats:
    """What one observer's scored images of the window starting at ``a`` (s) showed: the
    largest scan statistic, and the sum of their nominal variances over their number."""

    a: float
    z_max: float = 0.0
    var_sum: float = 0.0
    images: int = 0

    def add(self, z: float, sigma_e: float, sigma_b: float) -> None:
        self.z_max = max(self.z_max, z)
        self.var_sum += sigma_e * sigma_e + sigma_b * sigma_b
        self.images += 1


def image_false_alarm(scenario: Scenario, tests: int) -> float:
    """The sequential test's false-alarm probability per image: its share (one of ``tests``
    fused tests) of ``fdir.false_alarms_per_observer_hour`` over the images of an hour (one
    every ω_mid period)."""
    cfg = scenario.fdir
    return min(cfg.false_alarms_per_observer_hour / max(tests, 1)
               / (3600.0 * scenario.rates.mid_hz), 0.5)


class SequentialTest:
    """The scans of every observer against the nominal ``twin``, the threshold c from the
    per-image false-alarm probability ``q_image`` (:func:`image_false_alarm`)."""

    def __init__(self, scenario: Scenario, twin: TwinModel, q_image: float) -> None:
        self.settings = WindowTestSettings.of(scenario)
        self.seed = scenario.seed
        self.twin = twin
        self.c = scan_threshold_for(q_image)
        self.noise_var = clipped_noise_moments(scenario.camera.noise_frac)[1]
        self._scans: dict[int, ScanBuffer] = {}
        self.image_period_s = 1.0 / scenario.rates.mid_hz
        self._models: dict[int, tuple[float, RatioModel | None, np.ndarray]] = {}
        """each observer's window start (s), its ratio model and the times of its poses"""
        self._stats: dict[int, _WindowStats] = {}
        """each observer's scored images of its latest window"""
        self.c_nis = scan_threshold_for(q_image, sides=1)
        self._nis: dict[int, _NisScan] = {}

    def score_nis(self, spacecraft: int, updates: list[tuple[float, float]], judged: bool,
                  a: float) -> Crossing | None:
        """Observer ``spacecraft``'s nav updates ``updates`` ((time s, NIS), time order) not
        yet looked at pushed onto its NIS scan one by one (docs/fdir.md, "The nav's NIS,
        scanned too"), to the first at which the scan crosses ``c_nis`` (that update's
        crossing), or None; each counted in the record of the window starting at ``a`` (s),
        the one being collected.  ``judged`` False (its fault declared): looked at, not
        scored, and its scan starts afresh."""
        scan = self._nis.setdefault(spacecraft, _NisScan())
        fresh = [(t, v) for t, v in updates if t > scan.last_t + TIME_TOL_S]
        if fresh:
            scan.last_t = fresh[-1][0]
        if not judged:
            scan.values = []
            return None
        keep = max(SCAN_LENGTHS) - 1
        for t, v in fresh:
            scan.values = [*scan.values[-keep:], v]
            result = chi2_scan(scan.values, NIS_DOF)
            z = result.z if result is not None else 0.0
            held = scan.window if scan.window is not None and abs(scan.window[0] - a) <= \
                TIME_TOL_S else (a, 0.0)
            scan.window = (a, max(held[1], z))
            if result is not None and result.z > self.c_nis:
                n = result.span
                mean = float(np.mean(scan.values[-n:])) / NIS_DOF
                scan.values = []  # its evidence spent
                return Crossing(t, result, mean,
                                chi2_span_limit(self.c_nis, NIS_DOF, n) / (n * NIS_DOF), "nis")
        return None

    def window_fields(self, spacecraft: int, a: float) -> dict[str, float]:
        """The scans' record of observer ``spacecraft``'s window starting at ``a`` (s), the
        latest it scored (docs/fdir.md, "Each fault against the bound"), as
        ``FdirWindow``'s ``scan_z_max``, ``scan_threshold`` and ``image_sigma`` (none when no
        image of it was scored), ``nis_scan_z_max`` and ``nis_scan_threshold`` (none when no
        nav update)."""
        out: dict[str, float] = {}
        stats = self._stats.get(spacecraft)
        if stats is not None and abs(stats.a - a) <= TIME_TOL_S and stats.images:
            out |= {"scan_z_max": stats.z_max, "scan_threshold": self.c,
                    "image_sigma": math.sqrt(stats.var_sum / stats.images)}
        nis = self._nis.get(spacecraft)
        if nis is not None and nis.window is not None and abs(nis.window[0] - a) <= TIME_TOL_S:
            out |= {"nis_scan_z_max": nis.window[1], "nis_scan_threshold": self.c_nis}
        return out

    def last_scored_s(self, spacecraft: int) -> float:
        """The time of observer ``spacecraft``'s last image looked at (scored or passed
        over), s."""
        scan = self._scans.get(spacecraft)
        return scan.last_t if scan is not None else -math.inf

    def evidence_since(self, spacecraft: int, a: float) -> bool:
        """Whether observer ``spacecraft`` has an image scored at or after ``a`` (s): its
        evidence counts in the window starting there (the common-mode rule, Eq. 6)."""
        scan = self._scans.get(spacecraft)
        return scan is not None and scan.scored_t >= a - TIME_TOL_S

    def passed(self, spacecraft: int, t: float) -> None:
        """Observer ``spacecraft``'s images up to ``t`` (s) pass unscored (none can be judged:
        a slew, no plan known)."""
        scan = self._scans.setdefault(spacecraft, ScanBuffer())
        scan.last_t = max(scan.last_t, t)

    def reset(self, spacecraft: int) -> None:
        """Observer ``spacecraft``'s scan starts afresh (its crossing decided), keeping the
        times of its last images."""
        old = self._scans.get(spacecraft, ScanBuffer())
        self._scans[spacecraft] = ScanBuffer(last_t=old.last_t, scored_t=old.scored_t)

    def plan_times(self, a: float, b: float) -> np.ndarray:
        """The times (s) of window [a, b)'s images the ratio model draws on: one every ω_mid
        period, those the pose draws image (``gnc.hardware_threshold.imaged``)."""
        return imaged(np.arange(a, b - TIME_TOL_S, self.image_period_s))

    def modelled(self, spacecraft: int, a: float) -> bool:
        """Whether observer ``spacecraft``'s ratio model of the window starting at ``a`` (s)
        is drawn already (its plan is then not needed)."""
        held = self._models.get(spacecraft)
        return held is not None and abs(held[0] - a) < TIME_TOL_S

    def score(self, ctx: WindowContext, plan: np.ndarray | None) -> Crossing | None:
        """Score ``ctx``'s images (those of its observer not yet scored, in time order): the
        first at which the scan crosses c, or None.  ``plan``: the planned positions (K, 3) at
        :meth:`plan_times` (None: not known there), where the ratio model is drawn."""
        scan = self._scans.setdefault(ctx.spacecraft, ScanBuffer())
        pose = ctx.pose()
        prec = self.twin.precision(pose.planned, pose.boresights())
        model, times = self._model(ctx, plan)
        if model is None:
            scan.last_t = float(ctx.times[-1])
            return None
        gains = np.array([delta_h(ctx.psi[poi], ctx.phi[poi], p) for poi, p in ctx.seen])
        evidence = image_evidence(gains, prec * (ctx.phi * ctx.psi), model.mean, self.noise_var)
        at = ctx.times[evidence.kept]
        crossing = self._push(ctx, at, evidence, pose_spreads_at(model, times, at))
        if crossing is None:
            scan.last_t = float(ctx.times[-1])
        return crossing

    def _push(self, ctx: WindowContext, at: np.ndarray, evidence: ImageEvidence,
              sigma_b: np.ndarray) -> Crossing | None:
        """The images at ``at`` (s) pushed onto the observer's scan one by one until the scan
        crosses c (that image's crossing), each counted in the window's record."""
        scan = self._scans[ctx.spacecraft]
        stats = self._stats.get(ctx.spacecraft)
        if stats is None or abs(stats.a - ctx.a) > TIME_TOL_S:
            stats = self._stats[ctx.spacecraft] = _WindowStats(ctx.a)
        for t, rk, ek, bk in zip(at, evidence.residuals, evidence.sigma_e, sigma_b, strict=True):
            scan.push(float(rk), float(ek), float(bk), float(t))
            result = scan.scan()
            stats.add(result.z if result is not None else 0.0, float(ek), float(bk))
            if result is not None and result.z > self.c:
                shift = float(np.mean(scan.r[-result.span:]))
                return Crossing(float(t), result, shift, self.c * abs(shift) / result.z)
        return None

    def _model(self, ctx: WindowContext, plan: np.ndarray | None
               ) -> tuple[RatioModel | None, np.ndarray]:
        """The ratio model of the observer's window and the times of the poses it imaged:
        drawn once a window, on the planned poses at :meth:`plan_times` (on the first scored
        images where the plan is not known there), with the pose spreads the observer
        reports there."""
        held = self._models.get(ctx.spacecraft)
        if held is not None and self.modelled(ctx.spacecraft, ctx.a):
            return held[1], held[2]
        rng = np.random.default_rng([self.seed, ctx.spacecraft, int(round(ctx.a)), 2])
        times = self.plan_times(ctx.a, ctx.b) if plan is not None else ctx.times
        model = pose_ratio_model(ctx.pose(), self.twin, ctx.psi, ctx.phi, None, self.settings,
                                 rng, plan)
        self._models[ctx.spacecraft] = (ctx.a, model, imaged(times))
        return model, imaged(times)


def decided(crossings: dict[int, Crossing], scored: list[int], looked_s: dict[int, float],
            final: bool) -> list[int] | None:
    """Which observers' ``crossings`` (pending, by observer) are decided now, given the
    observers ``scored`` in the window (their images scored in it, not declared) and the time
    of the last image looked at of each (``looked_s``): a crossing waits until every other
    scored observer has been looked at past its image, unless the window's data is all in
    (``final``).  None when every scored observer (two or more) crossed the same way: a
    change no single observer explains, left to the window's global check (Eq. 6)."""
    ways = {c.direction for c in crossings.values()}
    if len(scored) > 1 and set(scored) <= set(crossings) and len(ways) == 1:
        return None
    return sorted(sc for sc, crossing in crossings.items()
                  if final or all(looked_s[o] >= crossing.image_t_s
                                  for o in scored if o != sc))
