"""The FDIR pipeline's link checks (docs/fdir.md, "Link and data faults"): an observer's data
that does not reach the ground is a link fault, never zero information gain.

* **Loss**: more of a window's observations missing by sequence number (the observer numbers
  every message it publishes on its key) than the link's nominal loss allows
  (``observer.loss_limit``: ``comms.packet_loss`` plus ``fdir.loss_tol`` plus its spread),
  for ``fdir.checks_persistence`` windows.
* **Silence**: an observer with a plan that sends no image for ``fdir.silent_windows``
  windows in a row (once per episode).
* **Store overflow** (ground passes): a window whose reports the observer's onboard store
  lost is a link fault of known cause (once per episode), never judged for information.
"""

from __future__ import annotations

import logging

from ground.fdir.observer import ObserverState, loss_limit
from ground.fdir.threshold import Persistence
from interfaces.contracts.messages import FaultReport, PoiObservations
from interfaces.contracts.scenario import Scenario


class LinkChecks:
    """Loss and silence of every observer, window by window; ``judge`` returns the link
    faults it declares."""

    def __init__(self, scenario: Scenario, node: str, log: logging.Logger) -> None:
        self.cfg = scenario.fdir
        self.comms = scenario.comms
        self.node = node
        self.log = log
        self.loss = Persistence(self.cfg.checks_persistence)

    def judge(self, sc: int, obs: ObserverState, images: list[PoiObservations],
              planned: bool, b: float) -> tuple[int, list[FaultReport]]:
        """One observer's window ending at b (s): its received ``images`` and whether a plan
        is in force.  Returns the observations lost and the link faults declared."""
        lost, reports = self._loss(sc, obs, images, b)
        if planned and not images:
            reports += self._silence(sc, obs, b)
        elif planned:
            obs.silent, obs.link_declared = 0, False
        obs.overflow_declared = False
        return lost, reports

    def limit(self, sent: int) -> float:
        """The link's loss limit for ``sent`` observations (``observer.loss_limit``)."""
        burst = self.comms.burst.mean_length_packets if self.comms.burst else 1.0
        return loss_limit(self.comms.packet_loss, burst, self.cfg.loss_tol, sent)

    def _loss(self, sc: int, obs: ObserverState, images: list[PoiObservations], b: float
              ) -> tuple[int, list[FaultReport]]:
        if not images:
            return 0, []
        seqs = sorted(m.seq for m in images)
        if obs.resync:  # the numbers the store lost were declared as its overflow
            obs.last_seq, obs.resync = max(obs.last_seq, seqs[0] - 1), False
        lost = obs.count_observations(seqs)
        if obs.silent:  # the gap is the silence already judged (a link fault), not loss
            return 0, []
        fraction = lost / (lost + len(seqs))
        limit = self.limit(lost + len(seqs))
        if not self.loss.update(sc, fraction > limit):
            return lost, []
        self.log.warning("FDIR: sc%d lost %.0f%% of its observations: link fault", sc,
                         100.0 * fraction)
        return lost, [FaultReport(sender=self.node, t_sim=b, spacecraft=sc, fault_class="link",
                                  metric=fraction, threshold=limit, window_end_s=b)]

    def overflow(self, sc: int, obs: ObserverState, b: float) -> list[FaultReport]:
        """A window whose reports the observer's onboard store lost to overflow (ground
        passes): a link fault of known cause, declared once per episode; the window is judged
        neither for silence nor for information."""
        obs.silent, obs.resync = 0, True
        if obs.overflow_declared:
            return []
        obs.overflow_declared = True
        self.log.warning("FDIR: sc%d's onboard store lost its reports before %.0f s: link "
                         "fault (store overflow)", sc, b)
        return [FaultReport(sender=self.node, t_sim=b, spacecraft=sc, fault_class="link",
                            window_end_s=b, cause="store_overflow")]

    def _silence(self, sc: int, obs: ObserverState, b: float) -> list[FaultReport]:
        obs.silent += 1
        if obs.silent < self.cfg.silent_windows or obs.link_declared:
            return []
        obs.link_declared = True
        self.log.warning("FDIR: sc%d silent for %d windows: link fault", sc, obs.silent)
        return [FaultReport(sender=self.node, t_sim=b, spacecraft=sc, fault_class="link",
                            window_end_s=b)]
