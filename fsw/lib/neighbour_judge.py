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
from itertools import pairwise

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
    GuidanceStatus,
    NeighbourDeclaration,
    NeighbourRuling,
    NeighbourVerdict,
    PoiObservations,
    ReportedPose,
    Unjudged,
)


def judge(subject: int, images: list[PoiObservations], pro: Pro | Unjudged, psi: np.ndarray,
          phi: np.ndarray, twin: TwinModel, n_rad_s: float, cfg: WindowTestSettings,
          rng: np.random.Generator, tests: int = 1) -> NeighbourVerdict:
    """The verdict on ``subject``'s window from the ``images`` it shared (time order), the PRO
    it held over the whole window (``pro``; else why there is none: :func:`held_pro`), ψ and
    φ of the judge's map at the window start: the window test (``gnc/window_test.py``) on the
    pose the images report, at the information test's false-alarm share (one of ``tests``:
    with the sequential test, the image scan has the other)."""
    usable = [m for m in images if m.pose is not None and m.pose.tracking_s >= cfg.settle_s]
    if not isinstance(pro, Pro) or not usable:
        why = pro if not isinstance(pro, Pro) else "not_tracking"
        return NeighbourVerdict(subject=subject, images=len(usable), unjudged=why)
    times = np.array([m.image_t_s for m in usable])
    pose = reported_pose(pro.states(n_rad_s, times)[:, :3],
                         [m.pose for m in usable if m.pose is not None])
    info = information([m.arrays() for m in usable], pose, psi, phi, twin)
    hw = hardware_threshold(pose, twin, psi, phi, info.prec, cfg, cfg.false_alarm(tests), rng)
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


@dataclass(frozen=True)
class FlownReport:
    """What a neighbour's guidance status says it flies at ``t_s`` (s): the assignment, the
    mode and the PRO (``GuidanceStatus``)."""

    t_s: float
    assignment_id: int
    mode: str
    pro: Pro | None

    @classmethod
    def of(cls, msg: GuidanceStatus) -> FlownReport:
        return cls(msg.t_sim, msg.assignment_id, msg.mode,
                   Pro.of(msg.pro) if msg.pro is not None else None)


def held_pro(reports: list[FlownReport], a: float, b: float, max_gap_s: float
             ) -> Pro | Unjudged:
    """The PRO a neighbour held over all of [a, b] (s) by its own reports (time order), or why
    none: ``plan_unknown`` unless reports at most ``max_gap_s`` apart cover [a, b] (one before
    or at a, one within ``max_gap_s`` of b); ``transfer`` when one of them is a transfer or a
    change of assignment; ``no_plan`` when one flies none (idle, safe hold).  The neighbours
    judge only held PROs: a transfer's path is the neighbour's own (docs/fdir.md, "Neighbours
    judge each other")."""
    before = [r for r in reports if r.t_s <= a]
    inside = [r for r in reports if a < r.t_s <= b]
    if not before or a - before[-1].t_s > max_gap_s:
        return "plan_unknown"
    span = [before[-1], *inside]
    times = [r.t_s for r in span] + [b]
    if max(t1 - t0 for t0, t1 in pairwise(times)) > max_gap_s:
        return "plan_unknown"
    if any(r.mode == "transfer" or r.assignment_id != span[0].assignment_id for r in span):
        return "transfer"
    pro = span[0].pro
    return pro if pro is not None and all(r.mode == "hold" for r in span) else "no_plan"


def agreed(verdicts: dict[int, bool | None], agree: int) -> list[int] | None:
    """The judges that declare the subject's window failed (sorted), or None when they do not
    agree: ``verdicts`` by judge (None: undecided); at least ``agree`` failed and more than
    half of those decided, or the only one decided."""
    decided = [j for j, v in verdicts.items() if v is not None]
    failed = sorted(j for j, v in verdicts.items() if v)
    need = 1 if len(decided) == 1 else max(agree, len(decided) // 2 + 1)
    return failed if failed and len(failed) >= need else None


def cleared(verdicts: dict[int, bool | None], agree: int) -> bool:
    """Whether the judges agree that a declared subject's window passed: the agreement rule
    (:func:`agreed`) applied to the verdicts that found it passing."""
    return agreed({j: None if v is None else not v for j, v in verdicts.items()},
                  agree) is not None


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
        """This spacecraft's declaration: its subject is left out from the window's end, or
        its start where the judges' scans declared it mid-window (never the spacecraft
        itself: its own observations are its own)."""
        if msg.subject != own:
            self.exclude(msg.subject, msg.t_end_s if msg.crossed_s is None else msg.t_start_s)

    def ruled(self, msg: NeighbourRuling) -> list[PoiObservations]:
        """The ground's ruling: what to fuse now (all that was held, when overruled)."""
        return self.readmit(msg.subject) if msg.verdict == "overruled" else []
