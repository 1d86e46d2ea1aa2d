"""The FDIR pipeline's data-integrity check (docs/fdir.md): the H_i each observer reports
(``InfoCostTelemetry``) at an FDI window boundary against the contribution the ground computes
from the observations it received.

The ground's map then holds every image before the boundary that came down.  Each observer's
report is recomputed on the view it fused (``fused_views.py``: its own images and those of
the observers in crosslink range when they were taken), every observer's precision scaled up
by the share of its observations lost on the way (sequence gaps, and its store's overflow),
and each neighbour's part of each view scaled to the count of its images the observer says it
fused (``shared_by``: what the crosslinks lost into it, ``fused_views.fused_shares``),
so ψ is as consistent as the ground can make it: the observer's H_i holds all of its images.
Without it a packet-loss fault on an observer's links, which starves its view of its
neighbours' images, read as a corrupt report (space campaign, faults 0038 and 0098); and with
one count for all neighbours a healthy neighbour of such an observer, short of that observer's
images alone, could (a 5-observer sketch: 14% off at the median, up to 136%).
The two then differ only by what the scalings miss, so a relative difference above
``fdir.integrity_tol`` is an inconsistent report, and ``fdir.checks_persistence`` of them in
a row a data-integrity fault.

The recomputation holds only while the ground has nearly every observation: ψ depends on every
observer's images, and lost ones are lost in bursts, from particular views, which no uniform
rescaling restores (at 30% loss in bursts of 50 packets a healthy report differed from it by a
median 11%, up to 55%).  While more than ``fdir.integrity_max_loss`` of any observer's
observations are missing, or any observer's latest window lost more than its link's nominal
loss explains (``link_checks.LOSSY_TAIL``: a link fault loses its share there long before the
run's total shows it), no report is judged (counted in ``unjudged``, logged).  The same
holds for the crosslinks: each observer fused its neighbours' images less the crosslinks'
nominal loss (``comms.packet_loss``), which the ground cannot tell image by image; above
``fdir.integrity_max_loss`` no report is judged either (at 13% on the paper's set-up under
passes, whose dumps lose nothing, honest reports differed from the recomputation by 20.0-20.2%
and three were declared corrupt).  Nor is the report of an observer that says it fused less
than 1 − ``fdir.integrity_max_loss`` of its neighbours' images in its range
(``crosslink_shortfall``): the count's rescaling holds for a few percent lost evenly, not
for most of a view (space campaign, after-pass-0000: a packet-loss fault of 86% on sc3's
links between passes, its honest reports 20.4% and 20.5% off, declared corrupt).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import numpy as np

from gnc.poi_map import PoiMap
from ground.fdir.fused_views import FusedViews
from ground.fdir.observer import ObserverState
from ground.fdir.threshold import Persistence
from interfaces.contracts.messages import FaultReport, InfoCostTelemetry, Unjudged
from interfaces.contracts.scenario import FdirSettings


class IntegrityCheck:
    """The observers' H_i reports awaiting their boundary, and the check's persistence."""

    def __init__(self, cfg: FdirSettings, node: str, log: logging.Logger,
                 period_s: float = math.inf, crosslink_loss: float = 0.0) -> None:
        self.cfg = cfg
        self.period_s = period_s
        """the FDI window's length, s (inf: every observer counts as heard)"""
        self.crosslink_loss = crosslink_loss
        """the crosslinks' nominal loss (``comms.packet_loss``)"""
        self.node = node
        self.log = log
        self.persistence = Persistence(cfg.checks_persistence)
        self.unjudged: dict[Unjudged, int] = {}
        """reports not judged, by reason"""
        self._reported: dict[tuple[int, int], InfoCostTelemetry] = {}
        """(observer, boundary) -> its report"""

    def reported(self, msg: InfoCostTelemetry, boundary: int) -> None:
        """Keep the H_i ``msg`` reports at window boundary ``boundary``, with the counts of
        its neighbours' images it fused."""
        self._reported[(msg.spacecraft, boundary)] = msg

    def check(self, j: int, b: float, settled: PoiMap, views: FusedViews,
              observers: dict[int, ObserverState],
              excludes: Callable[[int], bool] = lambda sc: False
              ) -> tuple[list[FaultReport], dict[int, Unjudged]]:
        """Judge the reports at boundary ``j`` (time b, s) against ``settled``, the ground's
        map holding every image before b that came down, each on the view its observer fused
        (``views``: ``fused_views.py``); returns the data-integrity faults
        declared and, by observer, why its report was not judged (module docstring).  No
        report is judged while any observer's reports before b are still aboard (the map
        lacks them), or more of any observer's observations are lost than
        ``fdir.integrity_max_loss`` (on the link or to its store's overflow, or the
        crosslinks' nominal loss is more), or any observer's latest window lost more than its
        link's nominal loss explains (``ObserverState.lossy``); nor is the
        report of an observer that ``excludes`` a neighbour its neighbours declared (it fuses
        less than the ground), or that fused less than 1 − ``fdir.integrity_max_loss`` of its
        neighbours' images in range (``crosslink_shortfall``: its crosslinks lost them)."""
        lost = np.array([o.lost_fraction() for o in observers.values()])
        reports = {sc: self._reported.pop((sc, j), None) for sc in observers}
        shared = shared_counts(reports, len(observers))
        ground = views.contributions(settled, lost, shared)
        fused = views.fused_fraction(lost, shared)
        why = self._blocked(b, self.period_s, lost, observers)
        out: list[FaultReport] = []
        unjudged: dict[int, Unjudged] = {}
        for sc, report in reports.items():
            mine = float(ground[sc - 1])
            if report is None or mine <= 0.0:
                continue
            reported = report.h_i
            reason = why or ("excluded" if excludes(sc) else None) or (
                "crosslink_shortfall" if fused[sc - 1] < 1.0 - self.cfg.integrity_max_loss
                else None)
            if reason is not None:
                unjudged[sc] = reason
                self._unjudged(sc, reason, lost)
                continue
            deviation = abs(reported / mine - 1.0)
            if self.persistence.update(sc, deviation > self.cfg.integrity_tol):
                self.log.warning("FDIR: sc%d reports H_i %.4g, observations give %.4g: "
                                 "data integrity", sc, reported, mine)
                out.append(FaultReport(
                    sender=self.node, t_sim=b, spacecraft=sc, fault_class="data_integrity",
                    metric=deviation, threshold=self.cfg.integrity_tol, window_end_s=b))
        self._reported = {k: v for k, v in self._reported.items() if k[1] > j}
        return out, unjudged

    def _blocked(self, b: float, period_s: float, lost: np.ndarray,
                 observers: dict[int, ObserverState]) -> Unjudged | None:
        """Why no report at b (s) can be judged: reports still aboard; too much lost; or an
        observer not heard from since the window's start ``b - period_s`` (its images may
        have reached its neighbours over the crosslinks and never the ground, or not yet: the
        views cannot be rebuilt)."""
        if any(o.aboard_before(b) for o in observers.values()):
            return "aboard"
        if any(o.heard_s < b - period_s for o in observers.values()):
            return "not_heard"
        if self.crosslink_loss > self.cfg.integrity_max_loss:
            return "crosslink_loss"
        if any(o.lossy for o in observers.values()):
            return "lossy"
        return "lost" if float(lost.max(initial=0.0)) > self.cfg.integrity_max_loss else None

    def _unjudged(self, sc: int, reason: Unjudged, lost: np.ndarray) -> None:
        self.unjudged[reason] = self.unjudged.get(reason, 0) + 1
        count = sum(self.unjudged.values())
        if not (count == 1 or count % 100 == 0):
            return
        if reason == "crosslink_loss":
            self.log.info("FDIR: sc%d's H_i report not judged: the crosslinks lose %.0f%% "
                          "(data integrity needs at most %.0f%%; %d unjudged so far)", sc,
                          100 * self.crosslink_loss, 100 * self.cfg.integrity_max_loss, count)
        elif reason != "lost":
            self.log.info("FDIR: sc%d's H_i report not judged (%s; %d unjudged so far)", sc,
                          reason, count)
        else:
            self.log.info("FDIR: sc%d's H_i report not judged (%s): %.0f%% of sc%d's "
                          "observations lost (data integrity needs at most %.0f%%; %d unjudged "
                          "so far)", sc, reason, 100 * lost.max(initial=0.0),
                          int(np.argmax(lost)) + 1, 100 * self.cfg.integrity_max_loss, count)



def shared_counts(reports: dict[int, InfoCostTelemetry | None], n: int) -> np.ndarray:
    """The images of each observer j each observer i says it fused (N, N), from their
    ``shared_by`` (NaN: no report, or one that does not break its count down)."""
    out = np.full((n, n), math.nan)
    for sc, r in reports.items():
        if r is not None and (r.shared_by or r.shared_received == 0):
            out[sc - 1] = [r.shared_by.get(str(j), 0) for j in range(1, n + 1)]
    return out
