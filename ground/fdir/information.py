"""The FDIR pipeline's information test of one observer's window (paper Sec. III.B-E, Eq. 9,
11-12; docs/fdir.md): ΔH_i against the twin's ΔH_i^pred, H_m,i against the threshold in
force, the identification evidence, and the consistency tests fused with it.

* ΔH_i = Σ φψ σ⁻¹ over the observations of the window's judged images (``twin.delta_h``);
* ΔH_i^pred: the same sum for the same image times from the nominal twin -- each image at the
  plan's position, the camera on the aim point the observer reports, β = 1;
* H_m,i (Eq. 9) against the threshold in force (``WindowThreshold``): by default the hardware
  model's quantile (``gnc/hardware_threshold.py``), else Eq. 11-12's (``fdir.samples``
  pointings within ``fdir.eps_deg``), both archived, with the floor guard ``fdir.floor``;
  direction by Table 3;
* with ``fdir.fuse_guidance`` the window also fails on the nav-vs-plan, pointing and Δv-rate
  tests, and with ``fdir.fuse_nis`` on the Σ NIS of the nav's updates in the window against
  its χ² quantile (``ground/fdir/consistency.py``).

The evidence's cheap part is judged every window; the twin at the reported pose, the seen-set
overlap and the boresight fit only for a window that failed or must name a class
(``ground/fdir/identify.py``), from the same located cameras.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ground.fdir.consistency import failed_tests, nis_test
from gnc.hardware_threshold import position_sigma, ratio_model
from ground.fdir.identify import (
    Evidence,
    Tolerances,
    gap_evidence,
    located_cameras,
    pose_evidence,
)
from gnc.fdi_metric import direction, metric
from ground.fdir.observer import ObserverState
from ground.fdir.threshold import WindowThreshold, sampled_threshold
from gnc.twin import TwinModel, delta_h, planned_boresights
from ground.fdir.window import WindowContext
from interfaces.contracts.messages import FdirWindow
from interfaces.contracts.scenario import Scenario


@dataclass(frozen=True)
class Judgement:
    """One observer's judged window before the constellation check: the window message (its
    ``exceeded`` still unset), the identification evidence, the thresholds, and whether the
    information test could decide."""

    window: FdirWindow
    evidence: Evidence
    threshold: WindowThreshold

    @property
    def decided(self) -> bool:
        """Whether the information test could decide (a metric and a threshold)."""
        return self.window.metric is not None and self.window.threshold is not None


class InformationTest:
    """The information test of every observer's windows against the nominal ``twin``, with
    the false-alarm probability per window ``q_window`` of the hardware threshold and of the
    NIS test."""

    def __init__(self, scenario: Scenario, twin: TwinModel, q_window: float) -> None:
        self.cfg = scenario.fdir
        self.seed = scenario.seed
        self.noise_frac = scenario.camera.noise_frac
        self.twin = twin
        self.q_window = q_window
        self.tol = Tolerances.of(self.cfg)

    def judge(self, ctx: WindowContext, obs: ObserverState, window: FdirWindow,
              identifying: bool, naming: bool) -> Judgement:
        """The judged ``window`` of ``ctx``: ``identifying``, its observer's declared fault
        still has no class (the full evidence every window); ``naming``, a failed window
        would have to name one (the boresight fit too)."""
        psi, phi, h_prev = ctx.psi, ctx.phi, ctx.h_prev
        dh = sum(delta_h(psi[poi], phi[poi], prec) for poi, prec in ctx.seen)
        prec = self.twin.precision(ctx.planned, planned_boresights(ctx.attitude, ctx.planned))
        dh_pred = delta_h(psi, phi, prec)
        m_val = metric(dh, dh_pred, h_prev)
        th = self.threshold(ctx, obs, prec)
        located = located_cameras(self.twin, ctx.seen)
        ev = pose_evidence(located, ctx.nav, ctx.attitude, ctx.planned, self.twin.radius_m,
                           obs.dv_rate(ctx.a, ctx.b))
        failed = [] if m_val is None or th.tau is None or m_val <= th.tau else ["information"]
        if self.cfg.fuse_guidance:
            failed += failed_tests(ev, self.tol)
        nis = nis_test(obs.nis_between(ctx.a, ctx.b), self.q_window) if self.cfg.fuse_nis \
            else None
        if nis is not None and nis[0] > nis[1]:
            failed.append("nis")
        if failed or identifying:
            ev = gap_evidence(ev, self.twin, ctx.seen, located, ctx.nav, ctx.attitude, psi, phi,
                              (dh, dh_pred), fit_boresight=naming)
        window = window.model_copy(update={
            "dh": dh, "dh_pred": dh_pred, "metric": m_val, "threshold": th.tau,
            "direction": direction(dh, dh_pred, h_prev), "evidence": ev.as_dict(),
            "threshold_model": th.model_tau, "threshold_sampled": th.sampled,
            "threshold_by": th.by, "failed": failed,
            "nis_sum": nis[0] if nis else None, "nis_limit": nis[1] if nis else None,
            "ratio_mean": th.model.mean if th.model else None,
            "ratio_std": th.model.std if th.model else None})
        return Judgement(window, ev, th)

    def threshold(self, ctx: WindowContext, obs: ObserverState, prec: np.ndarray
                  ) -> WindowThreshold:
        """Both thresholds of the window -- Eq. 11-12's ε-sampling and the hardware model's
        quantile -- and the one in force: the selected one (``fdir.threshold``), raised to the
        floor guard where it is below.  ``prec``: the twin's predicted precisions.  The
        model's pointing spread is the loop's jitter, the reported attitude knowledge and the
        pointing error the observer reports in the window (up to ``fdir.pointing_tol_deg``,
        beyond which the pointing test decides): the first window after the initial
        acquisition still holds the loop's transient (0.13° against 0.01° later), which the
        jitter alone does not cover."""
        cfg, sc, a = self.cfg, ctx.spacecraft, int(round(ctx.a))
        pos, att = ctx.planned, ctx.attitude
        sampled = sampled_threshold(self.twin, pos, planned_boresights(att, pos), ctx.psi,
                                    ctx.phi, ctx.h_prev, math.radians(cfg.eps_deg), cfg.samples,
                                    0.0, np.random.default_rng([self.seed, sc, a]))
        aims = att[:, 4:7] if att is not None else np.zeros_like(pos)
        nav_sigma = obs.nav_sigma.at(ctx.times)
        knowledge = float(np.mean(att[:, 7])) if att is not None else 0.0
        tracking = min(float(np.median(att[:, 3])) if att is not None else 0.0,
                       math.radians(cfg.pointing_tol_deg))  # beyond: the pointing test's
        model = ratio_model(
            self.twin, pos, aims, ctx.psi, ctx.phi,
            position_sigma(cfg.transfer_sigma_m if ctx.moving else cfg.track_sigma_m,
                           float(np.mean(nav_sigma)) if nav_sigma is not None else 0.0,
                           None if ctx.nav is None else ctx.nav - pos, cfg.position_tol_m),
            math.hypot(math.radians(cfg.pointing_jitter_deg), knowledge, tracking),
            self.noise_frac, cfg.model_samples,
            np.random.default_rng([self.seed, sc, a, 1]), prec)
        model_tau = model.threshold(self.q_window) if model is not None else None
        hardware = cfg.threshold == "hardware"
        return WindowThreshold.choose(model, model_tau, sampled,
                                      model_tau if hardware else sampled,
                                      "model" if hardware else "sampled", cfg.floor)
