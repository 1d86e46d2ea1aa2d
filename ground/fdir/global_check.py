"""The FDIR pipeline's global check (paper Eq. 6; ``ground/fdir/constellation.py`` holds the
test): every FDI window, the constellation's ratio over the judged observers against its
model, published as a ``ConstellationWindow`` with the ground map's cost and the running
shortfall; an information excess no single observer explains is declared once per episode on
the constellation (spacecraft 0, ``common_mode``), after ``fdir.persistence`` windows, or at
once when the sequential test's scans of every observer cross the same way
(:meth:`GlobalCheck.declare_crossings`).
"""

from __future__ import annotations

import logging

from gnc.image_scan import Crossing
from ground.fdir.constellation import ConstellationVerdict, ObserverGain, constellation_check
from ground.fdir.information import Judgement
from ground.fdir.threshold import Persistence
from interfaces.contracts.messages import ConstellationWindow, FaultReport, Message
from interfaces.contracts.scenario import FdirSettings


class GlobalCheck:
    """The global check's state: the constellation's persistence counter and the running
    shortfall, with the per-window false-alarm probability ``q_window``."""

    def __init__(self, cfg: FdirSettings, q_window: float, node: str, log: logging.Logger
                 ) -> None:
        self.persistence = Persistence(cfg.persistence, cfg.persistence_window)
        self.q_window = q_window
        self.node = node
        self.log = log
        self.way: str | None = None
        """the direction of the common-mode episode declared (None: none declared)"""
        self.shortfall = 0.0
        """Σ over judged windows of (ΔH^pred − ΔH) over the constellation: the running
        integral of Eq. 6's H − H_nom to first order"""

    def check(self, a: float, b: float, judged: dict[int, Judgement], cost: float
              ) -> tuple[ConstellationVerdict | None, list[Message]]:
        """The window [a, b)'s verdict over the ``judged`` observers, and its messages;
        ``cost``: H of the ground's fused map (Eq. 4, 7)."""
        gains = [ObserverGain(sc, j.window.dh, j.window.dh_pred, j.threshold.model)
                 for sc, j in judged.items()
                 if j.threshold.model is not None and j.window.dh_pred is not None
                 and j.window.dh is not None]
        verdict = constellation_check(gains, self.q_window)
        self.shortfall += sum(g.dh_pred - g.dh for g in gains)
        out: list[Message] = [ConstellationWindow(
            sender=self.node, t_sim=b, t_start_s=a, t_end_s=b, observers=len(gains),
            ratio=verdict.ratio if verdict else None,
            ratio_mean=verdict.model.mean if verdict else None,
            ratio_std=verdict.model.std if verdict else None,
            threshold=verdict.threshold if verdict else None,
            exceeded=verdict.exceeded if verdict else None,
            explained_by=verdict.explained_by if verdict else None,
            common_mode=verdict.common_mode if verdict else None,
            cost=cost, shortfall=self.shortfall)]
        declared = self.persistence.update(
            0, self.persistence.counted(0, verdict.common_mode if verdict else None, a))
        self.way = self.way if self.persistence.declared(0) else None
        if declared and verdict:
            self.way = "degraded" if verdict.ratio < verdict.model.mean else "improved"
            self.log.warning("FDIR: constellation fault at %.0f s: ΣΔH/ΣΔH_pred %.3g off its "
                             "nominal %.3g by more than τ %.3g on every observer: common mode",
                             b, verdict.ratio, verdict.model.mean, verdict.threshold)
            out.append(FaultReport(
                sender=self.node, t_sim=b, spacecraft=0, fault_class="common_mode",
                direction=self.way, metric=abs(1.0 - verdict.ratio),
                threshold=verdict.threshold, window_end_s=b))
        return verdict, out

    def declare_crossings(self, crossings: list[Crossing], t_s: float, window_end_s: float
                          ) -> list[FaultReport]:
        """The sequential test's scans of every observer scored in the window ending at
        ``window_end_s`` crossed the same way by ``t_s`` (s): a change no single observer
        explains (Eq. 6's verdict, reached image by image), declared on the constellation at
        once, unless its episode is already declared; the window's global check then carries
        the episode on (docs/fdir.md, "The sequential test")."""
        if self.persistence.declared(0) or not crossings:
            return []
        self.persistence.declare(0, t_s)
        way = self.way = crossings[0].direction
        self.log.warning("FDIR: constellation fault at %.0f s: the scans of %d observers crossed "
                         "together (%s): common mode", t_s, len(crossings), way)
        return [FaultReport(
            sender=self.node, t_sim=t_s, spacecraft=0, fault_class="common_mode",
            direction=way, metric=max(abs(c.shift) for c in crossings),
            threshold=max(c.limit for c in crossings), window_end_s=window_end_s,
            detector="sequential", evidence={"observers": float(len(crossings))})]

    def explains(self, crossing: Crossing) -> bool:
        """Whether an observer's scan ``crossing`` is the constellation's common-mode episode
        still declared, which moves every observer's information the same way (its nominal
        model is off by the common factor until the episode ends): not the observer's own."""
        return self.way is not None and crossing.direction == self.way

