"""The FDIR pipeline's global check (paper Eq. 6; ``ground/fdir/constellation.py`` holds the
test): every FDI window, the constellation's ratio over the judged observers against its
model, published as a ``ConstellationWindow`` with the ground map's cost and the running
shortfall; an information excess no single observer explains is declared once per episode on
the constellation (spacecraft 0, ``common_mode``), after ``fdir.persistence`` windows.
"""

from __future__ import annotations

import logging

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
        if self.persistence.update(0, verdict.common_mode if verdict else None) and verdict:
            self.log.warning("FDIR: constellation fault at %.0f s: ΣΔH/ΣΔH_pred %.3g off its "
                             "nominal %.3g by more than τ %.3g on every observer: common mode",
                             b, verdict.ratio, verdict.model.mean, verdict.threshold)
            out.append(FaultReport(
                sender=self.node, t_sim=b, spacecraft=0, fault_class="common_mode",
                direction="degraded" if verdict.ratio < verdict.model.mean else "improved",
                metric=abs(1.0 - verdict.ratio), threshold=verdict.threshold, window_end_s=b))
        return verdict, out
