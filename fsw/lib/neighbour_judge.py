"""The neighbours' judge aboard an observer (docs/fdir.md, "Neighbours judge each other"): one
neighbour's FDI window against its plan, on the judge's own fused map, and the agreement rule
that declares a fault.  Pure functions; ``fsw/apps/neighbours.py`` feeds them.

The test is the ground's window test (``gnc/window_test.py``) with what a neighbour has of
the subject:

* ΔH_j = Σ φ ψ σ⁻¹ over the observations the subject shared in the window, ψ held at the
  window start on the judge's fused map;
* ΔH_j^pred: the twin's images at the subject's assigned PRO at the same image times, its
  camera on the aim point it reports (``ReportedPose``), β = 1;
* τ from the same hardware model the ground uses, with the subject's reported nav 1σ, its
  offsets from the plan, its attitude knowledge and tracking error; the ground's floor guard
  below it.  Judged only on images taken while the subject's attitude had been tracking for
  ``fdir.settle_s`` and while it holds its PRO (its transfer's path is its own choice: not
  judged).
* with ``fdir.fuse_guidance`` (the ground's default), the pose tests the ground fuses with it,
  on the same reported pose: the median distance of the reported nav from the plan against
  ``fdir.position_tol_m`` (``plan``), and the median pointing error the attitude reports
  against ``fdir.pointing_tol_deg`` (``pointing``); the subject's Δv is not shared, so no
  ``dv_rate``.  A pointing actuator fault shows in the attitude estimate before it costs
  information; a small one may never (Fig. 26).

Agreement (``agreed``): a subject's window is declared failed when at least ``agree`` of the
neighbours that decided on it found it failed and they are more than half of them; when only
one decided, that one suffices.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gnc.pro import Pro
from gnc.twin import TwinModel
from gnc.window_test import (
    WindowPose,
    WindowTestSettings,
    exceeded,
    failed_tests,
    hardware_threshold,
    information,
)
from interfaces.contracts.messages import (
    NeighbourDeclaration,
    NeighbourRuling,
    NeighbourVerdict,
    PoiObservations,
    ReportedPose,
)


def judge(subject: int, images: list[PoiObservations], pro: Pro | None, psi: np.ndarray,
          phi: np.ndarray, twin: TwinModel, n_rad_s: float, cfg: WindowTestSettings,
          rng: np.random.Generator) -> NeighbourVerdict:
    """The verdict on ``subject``'s window from the ``images`` it shared (time order), its
    PRO in force over the whole window (``pro``; None: no plan, or a transfer), ψ and φ of
    the judge's map at the window start: the window test (``gnc/window_test.py``) on the pose
    the images report, at the information test's false-alarm share."""
    usable = [m for m in images if m.pose is not None and m.pose.tracking_s >= cfg.settle_s]
    if pro is None or not usable:
        return NeighbourVerdict(subject=subject, images=len(usable))
    times = np.array([m.image_t_s for m in usable])
    pose = reported_pose(pro.states(n_rad_s, times)[:, :3],
                         [m.pose for m in usable if m.pose is not None])
    info = information([m.arrays() for m in usable], pose, psi, phi, twin)
    hw = hardware_threshold(pose, twin, psi, phi, info.prec, cfg, cfg.false_alarm(), rng)
    tau = hw.tau if hw is not None else None
    failed = failed_tests(info, tau, pose, None, cfg)
    return NeighbourVerdict(subject=subject, images=len(usable), dh=info.dh,
                            dh_pred=info.dh_pred, metric=info.metric, threshold=tau,
                            exceeded=exceeded(failed, info.metric is not None and tau is not None),
                            direction=info.direction, failed=failed)


def reported_pose(planned: np.ndarray, poses: list[ReportedPose]) -> WindowPose:
    """The window's pose as the subject's observations report it, at the plan's positions
    ``planned`` (K, 3) of their image times."""
    return WindowPose(planned, np.array([p.aim_m for p in poses]),
                      np.array([p.nav_m for p in poses]),
                      np.array([p.nav_sigma_m for p in poses]),
                      np.array([p.tracking_rad for p in poses]),
                      np.array([p.knowledge_rad for p in poses]))


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
