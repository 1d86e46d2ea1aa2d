"""The neighbours' judge aboard an observer (docs/fdir.md, "Neighbours judge each other"): one
neighbour's FDI window against its plan, on the judge's own fused map, and the agreement rule
that declares a fault.  Pure functions; ``fsw/apps/neighbours.py`` feeds them.

The test is the ground's information test (Eq. 9) with what a neighbour has of the subject:

* ΔH_j = Σ φ ψ σ⁻¹ over the observations the subject shared in the window, ψ held at the
  window start on the judge's fused map (``gnc.twin.delta_h``);
* ΔH_j^pred: the twin's images at the subject's assigned PRO at the same image times, its
  camera on the aim point it reports (``ReportedPose``), β = 1;
* τ from the same hardware model the ground uses (``gnc.hardware_threshold.ratio_model``), with
  the subject's reported nav 1σ, its offsets from the plan, its attitude knowledge and tracking
  error; the ground's floor guard below it.  Judged only on images taken while the subject's
  attitude had been tracking for ``fdir.settle_s`` and while it holds its PRO (its transfer's
  path is its own choice: not judged).
* with ``fdir.fuse_guidance`` (the ground's default), the two pose tests the ground fuses with
  it, on the same reported pose: the median distance of the reported nav from the plan against
  ``fdir.position_tol_m`` (``plan``), and the median pointing error the attitude reports
  against ``fdir.pointing_tol_deg`` (``pointing``).  A pointing actuator fault shows in the
  attitude estimate before it costs information; a small one may never (Fig. 26).

Agreement (``agreed``): a subject's window is declared failed when at least ``agree`` of the
neighbours that decided on it found it failed and they are more than half of them; when only
one decided, that one suffices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gnc.fdi_metric import direction, metric
from gnc.hardware_threshold import position_sigma, ratio_model, window_false_alarm
from gnc.pro import Pro
from gnc.twin import TwinModel, aimed_boresights, delta_h
from interfaces.contracts.messages import (
    NeighbourDeclaration,
    NeighbourRuling,
    NeighbourVerdict,
    PoiObservations,
    ReportedPose,
)
from interfaces.contracts.scenario import Scenario


@dataclass(frozen=True)
class JudgeSettings:
    """What the judge takes from the scenario: the ground's hardware model and floor guard
    (``[fdir]``, ``[camera] noise_frac``), the false-alarm probability per window, and the
    settling time after a slew (s)."""

    settle_s: float
    track_sigma_m: float
    position_tol_m: float
    pointing_jitter_rad: float
    pointing_tol_rad: float
    noise_frac: float
    samples: int
    q_window: float
    floor: float
    pose_tests: bool

    @classmethod
    def of(cls, scenario: Scenario) -> JudgeSettings:
        cfg = scenario.fdir
        return cls(cfg.settle_s, cfg.track_sigma_m, cfg.position_tol_m,
                   math.radians(cfg.pointing_jitter_deg), math.radians(cfg.pointing_tol_deg),
                   scenario.camera.noise_frac, cfg.model_samples,
                   window_false_alarm(cfg.false_alarms_per_observer_hour,
                                      scenario.rates.fdi_period_s, cfg.persistence),
                   cfg.floor, cfg.fuse_guidance)


def judge(subject: int, images: list[PoiObservations], pro: Pro | None, psi: np.ndarray,
          phi: np.ndarray, twin: TwinModel, n_rad_s: float, cfg: JudgeSettings,
          rng: np.random.Generator) -> NeighbourVerdict:
    """The verdict on ``subject``'s window from the ``images`` it shared (time order), its
    PRO in force over the whole window (``pro``; None: no plan, or a transfer), ψ and φ of
    the judge's map at the window start."""
    usable = [m for m in images if m.pose is not None and m.pose.tracking_s >= cfg.settle_s]
    if pro is None or not usable:
        return NeighbourVerdict(subject=subject, images=len(usable))
    times = np.array([m.image_t_s for m in usable])
    planned = pro.states(n_rad_s, times)[:, :3]
    poses = [m.pose for m in usable if m.pose is not None]
    aims = np.array([p.aim_m for p in poses])
    prec = twin.precision(planned, aimed_boresights(aims, planned))
    dh = sum(delta_h(psi[m.arrays()[0]], phi[m.arrays()[0]], m.arrays()[1]) for m in usable)
    dh_pred = delta_h(psi, phi, prec)
    m_val = metric(dh, dh_pred)
    tau = _threshold(planned, aims, poses, psi, phi, prec, twin, cfg, rng)
    failed = [] if m_val is None or tau is None or m_val <= tau else ["information"]
    failed += pose_tests(planned, poses, cfg) if cfg.pose_tests else []
    decided = bool(failed) or (m_val is not None and tau is not None)
    return NeighbourVerdict(subject=subject, images=len(usable), dh=dh, dh_pred=dh_pred,
                            metric=m_val, threshold=tau, exceeded=bool(failed) if decided else None,
                            direction=direction(dh, dh_pred), failed=failed)


def pose_tests(planned: np.ndarray, poses: list[ReportedPose], cfg: JudgeSettings) -> list[str]:
    """The ground's pose tests on the subject's reported pose over the window: ``plan`` when
    the median distance of its nav from the plan (m) exceeds ``position_tol_m``, ``pointing``
    when its median reported pointing error exceeds ``pointing_tol_rad``."""
    nav = np.array([p.nav_m for p in poses])
    out = []
    if float(np.median(np.linalg.norm(nav - planned, axis=1))) > cfg.position_tol_m:
        out.append("plan")
    if float(np.median([p.tracking_rad for p in poses])) > cfg.pointing_tol_rad:
        out.append("pointing")
    return out


def _threshold(planned: np.ndarray, aims: np.ndarray, poses: list[ReportedPose], psi: np.ndarray,
               phi: np.ndarray, prec: np.ndarray, twin: TwinModel, cfg: JudgeSettings,
               rng: np.random.Generator) -> float | None:
    """τ of the hardware model for the window (the ground's, with the subject's reported
    pose), raised to the floor guard; None when the prediction holds no information."""
    nav = np.array([p.nav_m for p in poses])
    sigma = position_sigma(cfg.track_sigma_m, float(np.mean([p.nav_sigma_m for p in poses])),
                           nav - planned, cfg.position_tol_m)
    tracking = min(float(np.median([p.tracking_rad for p in poses])), cfg.pointing_tol_rad)
    knowledge = float(np.mean([p.knowledge_rad for p in poses]))
    model = ratio_model(twin, planned, aims, psi, phi, sigma,
                        math.hypot(cfg.pointing_jitter_rad, knowledge, tracking),
                        cfg.noise_frac, cfg.samples, rng, prec)
    if model is None:
        return None
    return max(model.threshold(cfg.q_window), cfg.floor)


def agreed(verdicts: dict[int, bool | None], agree: int) -> list[int] | None:
    """The judges that declare the subject's window failed (sorted), or None when they do not
    agree: ``verdicts`` by judge (None: undecided); at least ``agree`` failed and more than
    half of those decided, or the only one decided."""
    decided = [j for j, v in verdicts.items() if v is not None]
    failed = sorted(j for j, v in verdicts.items() if v)
    need = 1 if len(decided) == 1 else max(agree, len(decided) // 2 + 1)
    return failed if failed and len(failed) >= need else None


@dataclass
class Exclusions:
    """The observers left out of this spacecraft's fusion since its neighbours declared them
    (from the declared window's start, s), and what they sent since, held for the ground's
    ruling: overruled, it is fused after all."""

    since_s: dict[int, float] = field(default_factory=dict)
    held: dict[int, list[PoiObservations]] = field(default_factory=dict)

    def exclude(self, subject: int, from_s: float) -> None:
        self.since_s.setdefault(subject, from_s)

    def admits(self, msg: PoiObservations) -> bool:
        """Whether ``msg`` is fused; one of an excluded observer is held instead."""
        since = self.since_s.get(msg.spacecraft)
        if since is None or msg.image_t_s < since:
            return True
        self.held.setdefault(msg.spacecraft, []).append(msg)
        return False

    def readmit(self, subject: int) -> list[PoiObservations]:
        """The ground overruled: ``subject`` is fused again; returns what was held."""
        self.since_s.pop(subject, None)
        return self.held.pop(subject, [])

    def declared(self, msg: NeighbourDeclaration, own: int) -> None:
        """This spacecraft's declaration: its subject is left out from the window's end
        (never the spacecraft itself: its own observations are its own)."""
        if msg.subject != own:
            self.exclude(msg.subject, msg.t_end_s)

    def ruled(self, msg: NeighbourRuling) -> list[PoiObservations]:
        """The ground's ruling: what to fuse now (all that was held, when overruled)."""
        return self.readmit(msg.subject) if msg.verdict == "overruled" else []
