"""The FDIR pipeline's information test of one observer's window (paper Sec. III.B-E, Eq. 9,
11-12; docs/fdir.md): the window test the neighbours' judge runs too (``gnc/window_test.py``)
with the ground's additions, the identification evidence and the NIS test fused with it.

* ΔH_i = Σ φψ σ⁻¹ over the observations of the window's judged images, ΔH_i^pred the same sum
  for the same image times from the nominal twin -- each image at the plan's position, the
  camera on the aim point the observer reports, β = 1 (``gnc.window_test.information``);
* H_m,i (Eq. 9) against the threshold in force (``WindowThreshold``): by default the hardware
  model's quantile (``gnc.window_test.hardware_threshold``), else Eq. 11-12's
  (``fdir.samples`` pointings within ``fdir.eps_deg``), both archived, with the floor guard
  ``fdir.floor``; direction by Table 3;
* with ``fdir.fuse_guidance`` the window also fails on the nav-vs-plan, pointing and Δv-rate
  tests (``gnc.window_test.pose_tests``), and with ``fdir.fuse_nis`` on the Σ NIS of the
  nav's updates in the window against its χ² quantile (``ground/fdir/consistency.py``).

The evidence's cheap part is judged every window; the twin at the reported pose, the seen-set
overlap and the boresight fit only for a window that failed or must name a class
(``ground/fdir/identify.py``), from the same located cameras.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from gnc.twin import TwinModel, planned_boresights
from gnc.window_test import (
    WindowPose,
    WindowTestSettings,
    failed_tests,
    hardware_threshold,
    information,
)
from ground.fdir.consistency import nis_test
from ground.fdir.identify import (
    CameraFix,
    Evidence,
    gap_evidence,
    located_cameras,
    pose_evidence,
)
from ground.fdir.observer import ObserverState
from ground.fdir.threshold import WindowThreshold, sampled_threshold
from ground.fdir.window import WindowContext
from interfaces.contracts.messages import FdirWindow
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S


@dataclass(frozen=True)
class Judgement:
    """One observer's judged window before the constellation check: the window message (its
    ``exceeded`` still unset), the identification evidence, the thresholds, and whether the
    information test could decide."""

    window: FdirWindow
    evidence: Evidence
    threshold: WindowThreshold
    part: Evidence | None = None
    """the evidence of the window's images since a change within it (``evidence_part``;
    the window's ``evidence_since_s``), looked at first"""

    @property
    def decided(self) -> bool:
        """Whether the information test could decide (a metric and a threshold)."""
        return self.window.metric is not None and self.window.threshold is not None


class InformationTest:
    """The information test of every observer's windows against the nominal ``twin``: the
    window test (``gnc/window_test.py``) with the ground's additions.  ``q_window``: the
    false-alarm probability per window of the hardware threshold and of the NIS test, the
    budget split between them with ``fdir.fuse_nis``."""

    def __init__(self, scenario: Scenario, twin: TwinModel) -> None:
        self.cfg = scenario.fdir
        self.seed = scenario.seed
        self.settings = WindowTestSettings.of(scenario)
        self.twin = twin
        sequential = int(self.cfg.detector == "sequential")
        self.tests = 1 + int(self.cfg.fuse_nis) * (1 + sequential) + sequential
        """the statistical tests sharing the false-alarm budget: this one, the NIS test and
        the sequential scans (of the information, and of the NIS), as fused"""
        self.q_window = self.settings.false_alarm(self.tests)

    def judge(self, ctx: WindowContext, obs: ObserverState, window: FdirWindow,
              identifying: bool, naming: bool, since_s: float | None = None) -> Judgement:
        """The judged ``window`` of ``ctx``: ``identifying``, its observer's declared fault
        still has no class (the full evidence every window; and of its images at or after
        ``since_s``, s, the change the sequential test estimated: ``evidence_part``);
        ``naming``, a failed window would have to name one (the boresight fit too)."""
        psi, phi, pose = ctx.psi, ctx.phi, ctx.pose()
        info = information(ctx.seen, pose, psi, phi, self.twin, ctx.h_prev)
        th = self.threshold(ctx, pose, info.prec)
        located, ev = self._pose_evidence(ctx, pose, obs)
        failed = failed_tests(info, th.tau, pose, ev.dv_rate_mps2, self.settings)
        updates = obs.nis_between(ctx.a, ctx.b)
        nis = nis_test(updates, self.q_window) if self.cfg.fuse_nis else None
        if nis is not None and nis[0] > nis[1]:
            failed.append("nis")
        if failed or identifying:
            ev = gap_evidence(ev, self.twin, ctx.seen, located, ctx.nav, ctx.attitude, psi, phi,
                              (info.dh, info.dh_pred), fit_boresight=naming)
        part = evidence_part(ctx, since_s) if identifying else None
        part_ev = self._part_evidence(part, obs) if part is not None else None
        window = window.model_copy(update={
            "dh": info.dh, "dh_pred": info.dh_pred, "metric": info.metric, "threshold": th.tau,
            "direction": info.direction, "evidence": ev.as_dict(),
            "evidence_since_s": part.a if part is not None else None,
            "threshold_model": th.model_tau, "threshold_sampled": th.sampled,
            "threshold_by": th.by, "failed": failed,
            "nis_sum": nis[0] if nis else None, "nis_limit": nis[1] if nis else None,
            "nis_updates": len(updates) if nis else None,
            "ratio_mean": th.model.mean if th.model else None,
            "ratio_std": th.model.std if th.model else None})
        return Judgement(window, ev, th, part_ev)

    def _part_evidence(self, part: WindowContext, obs: ObserverState) -> Evidence:
        """The whole identification evidence of part of a window (``evidence_part``)."""
        pose = part.pose()
        info = information(part.seen, pose, part.psi, part.phi, self.twin, part.h_prev)
        located, ev = self._pose_evidence(part, pose, obs)
        return gap_evidence(ev, self.twin, part.seen, located, part.nav, part.attitude,
                            part.psi, part.phi, (info.dh, info.dh_pred), fit_boresight=True)

    def _pose_evidence(self, ctx: WindowContext, pose: WindowPose, obs: ObserverState
                       ) -> tuple[list[tuple[int, CameraFix]], Evidence]:
        """The cameras located from ``ctx``'s images and the evidence's cheap part
        (``ground.fdir.identify.pose_evidence``), the Δv spent over the context's span."""
        located = located_cameras(self.twin, ctx.seen)
        return located, pose_evidence(located, pose, self.twin.radius_m,
                                      obs.dv_rate(ctx.a, ctx.b))

    def threshold(self, ctx: WindowContext, pose: WindowPose, prec: np.ndarray
                  ) -> WindowThreshold:
        """Both thresholds of the window -- Eq. 11-12's ε-sampling and the hardware model's
        (``gnc.window_test.hardware_threshold``) -- and the one in force: the selected one
        (``fdir.threshold``), raised to the floor guard where it is below.  ``prec``: the
        twin's predicted precisions."""
        cfg, sc, a = self.cfg, ctx.spacecraft, int(round(ctx.a))
        pos = ctx.planned
        sampled = sampled_threshold(self.twin, pos, planned_boresights(ctx.attitude, pos),
                                    ctx.psi, ctx.phi, ctx.h_prev, math.radians(cfg.eps_deg),
                                    cfg.samples, 0.0, np.random.default_rng([self.seed, sc, a]))
        hardware = hardware_threshold(pose, self.twin, ctx.psi, ctx.phi, prec, self.settings,
                                      self.q_window,
                                      np.random.default_rng([self.seed, sc, a, 1]))
        return WindowThreshold.choose(hardware, sampled,
                                      "model" if cfg.threshold == "hardware" else "sampled",
                                      cfg.floor)


IDENTIFY_IMAGES = 10
"""The fewest judged images since the change the sequential test estimated that identify a
fault on their own (``evidence_part``): 10 s of images at 1 Hz, twice ``MIN_FIXES`` camera
fixes."""

IDENTIFY_STEP = 5
"""A declared fault without a class is tried again on part of a window once this many more
images have come (``ground.fdir.pipeline.FdirPipeline``)."""


def evidence_part(ctx: WindowContext, since_s: float | None) -> WindowContext | None:
    """The part of window ``ctx`` a fault is identified on, when the sequential test declared
    it within the window: its images at or after the change the scan estimated (``since_s``,
    s; ``gnc.image_scan.Crossing.change_s``), starting there (docs/fdir.md, "Identification
    after a crossing").  The evidence is medians over images, so a change late in a window
    would otherwise be outvoted by the nominal images before it.  None (the whole window):
    no change within the window, or fewer than ``IDENTIFY_IMAGES`` images since."""
    if since_s is None or since_s <= ctx.a + TIME_TOL_S:
        return None
    part = ctx.since(since_s)
    if len(part.times) < IDENTIFY_IMAGES:
        return None
    return replace(part, a=since_s)
