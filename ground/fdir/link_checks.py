"""The FDIR pipeline's link checks (docs/fdir.md, "Link and data faults"): an observer's data
that does not reach the ground is a link fault, never zero information gain.

* **Loss**: more of a window's observations missing by sequence number (the observer numbers
  every message it publishes on its key) than the link's nominal loss allows
  (``observer.loss_limit``: ``comms.packet_loss`` plus ``fdir.loss_tol`` plus its spread),
  for ``fdir.checks_persistence`` windows; the window after a silence counts the silence's
  missing observations too.  One window decides alone when a healthy link would lose as many
  with a probability (``observer.loss_tail``) below the window's false-alarm share of
  ``fdir.false_alarms_per_observer_hour`` (a link losing 6 of 7 observations at a nominal
  10%: 6e-6 against 8e-5 for 30 s windows and 0.01 per hour).
* **Silence**: an observer with its camera on that sends no image for ``fdir.silent_windows``
  windows in a row (once per episode, and not when its loss was declared already: one link
  fault, declared once), or for a window's time straddling two windows, judged when its
  images resume (a host's link cut for 30 s: docs/hosts.md).  One silent window
  decides alone when a healthy link would lose all of a window's images (one per ω_mid
  period) with a probability below the window's share, as for loss (30 images at a nominal
  15%: 2e-25; in bursts of 50 packets: 0.57, and the silence waits for
  ``fdir.silent_windows``).
* **Lossy windows**: a window whose loss a healthy link would reach with a probability below
  ``LOSSY_TAIL``, or a silent one, marks its observer ``lossy`` (``ObserverState.lossy``):
  the data-integrity check judges no report while one is (its loss is not spread over the
  run, so no rescaling of the ground's map rebuilds what the observers fused).
* **Silent in a pass** (ground passes): an observer of which nothing came down an FDI period
  and the FDIR's latency after a pass's acquisition, while others were heard in it (the dump
  brings the reports the FDIR judges first), has lost its link: declared then, once per
  episode, instead of at the pass's end, when its silent windows could first be judged.
* **Dump loss** (ground passes): the store sends a lost message again, so nothing is missing
  by sequence number; the loss shows in the store's accounting (sent again vs dumped) as it
  comes down with the ground's link counters.  Counted over ``rates.fdi_period_s`` of sim
  time at a time (the part of it a pass covers), a loss beyond the link's limit that a
  healthy link would reach with a probability below the window's share (``decisive``) is a
  link fault, declared once per episode (a dump window within the limit ends it).  Without
  it a packet-loss fault that began between passes was invisible to the ground (space
  campaign, fault-0028: 86% on a 15% link, every image in).
* **Out of the relay's reach**: the ground is reached through the target (``comms.range_m``
  of it), so an observer its plan puts beyond that range, less ``REACH_MARGIN_SIGMAS``
  transfer accuracies and the plan test's tolerance, at any of a window's image times sends
  nothing down, by design: the window is judged for neither loss nor silence (and the gap it
  leaves is counted afresh), nor is the observer's silence in a pass.  Without it, healthy
  observers of the paper's set-up on 18-20 m PROs with a 19 m range were declared link faults
  after one silent window (4 of 5 in 600 s).
* **Store overflow** (ground passes): a window whose reports the observer's onboard store
  lost is a link fault of known cause (once per episode), never judged for information.
"""

from __future__ import annotations

import logging
from itertools import pairwise

import numpy as np

from gnc.hardware_threshold import window_false_alarm
from ground.fdir.observer import ObserverState, loss_limit, loss_tail
from ground.fdir.threshold import Persistence
from interfaces.contracts.messages import FaultReport, PoiObservations, StoreCounter
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S

LOSSY_TAIL = 0.05
"""A window losing as many observations as a healthy link would with at most this probability
is lossy (one healthy window in twenty at most)."""
REACH_MARGIN_SIGMAS = 3.0
"""Transfer accuracies (``fdir.transfer_sigma_m``) by which a planned position must lie within
``comms.range_m`` of the target, beyond the plan test's tolerance, to count as in reach."""


class LinkChecks:
    """Loss and silence of every observer, window by window (``judge``), and with ground
    passes its silence in a pass (``pass_silence``), its dump's loss (``dump``) and its
    store's overflow (``overflow``): each returns the link faults it declares, one per
    episode across them (module docstring)."""

    def __init__(self, scenario: Scenario, node: str, log: logging.Logger) -> None:
        self.cfg = scenario.fdir
        self.comms = scenario.comms
        self.node = node
        self.log = log
        self.loss = Persistence(self.cfg.checks_persistence)
        self.alpha = window_false_alarm(self.cfg.false_alarms_per_observer_hour,
                                        scenario.rates.fdi_period_s, 1)
        """the false-alarm probability at which one window decides alone"""
        self.period_s = scenario.rates.fdi_period_s
        self.images_per_window = max(round(scenario.rates.fdi_period_s
                                           * scenario.rates.mid_hz), 1)
        """the images an observer takes in a window (one per ω_mid period)"""

    def in_reach(self, obs: ObserverState, n: float, a: float, b: float) -> bool:
        """Whether the observer's plan keeps it within the relay's reach over the window
        [a, b) (s) at its image times (module docstring); ``n``: the target's mean motion,
        rad/s.  Without a plan (the deployment, from the target) it is taken as in reach."""
        times = np.linspace(a, b, self.images_per_window, endpoint=False)
        planned = obs.planned(n, times)
        if planned is None:
            return True
        margin = self.cfg.position_tol_m + REACH_MARGIN_SIGMAS * self.cfg.transfer_sigma_m
        reach = self.comms.range_m - margin
        return bool(np.all(np.linalg.norm(planned[0], axis=1) <= reach))

    def judge(self, sc: int, obs: ObserverState, images: list[PoiObservations],
              expected: bool, b: float, reachable: bool = True
              ) -> tuple[int, list[FaultReport]]:
        """One observer's window ending at b (s): its received ``images``, whether any
        were ``expected`` (its camera on: it images every ω_mid period, with a plan or
        without), and whether its plan kept it in the relay's reach (``in_reach``; out of it
        nothing is judged and what it missed is counted afresh).  Returns the observations
        lost and the link faults declared."""
        if not reachable:
            if images:
                obs.received += len(images)
                obs.last_seq = max(obs.last_seq, max(m.seq for m in images))
            obs.resync, obs.silent, obs.lossy = True, 0, True
            obs.last_image_s = None
            self.loss.update(sc, False)
            return 0, []
        lost, reports = self._loss(sc, obs, images, b)
        obs.lossy = (loss_tail(lost, lost + len(images), self.comms.packet_loss, self.burst)
                     < LOSSY_TAIL) if images else expected
        if expected and not images:
            reports += self._silence(sc, obs, b)
        elif expected:
            reports += self._gap(sc, obs, images, b)
            obs.silent, obs.link_declared = 0, False
        if not expected or images:
            obs.last_image_s = max(m.t_sim for m in images) if expected else None
        obs.overflow_declared = False
        return lost, reports

    @property
    def burst(self) -> float:
        """The links' mean burst length, packets (1: Bernoulli loss)."""
        return self.comms.burst.mean_length_packets if self.comms.burst else 1.0

    def limit(self, sent: int) -> float:
        """The link's loss limit for ``sent`` observations (``observer.loss_limit``)."""
        return loss_limit(self.comms.packet_loss, self.burst, self.cfg.loss_tol, sent)

    def decisive(self, lost: int, sent: int) -> bool:
        """Whether a window losing ``lost`` of ``sent`` observations decides alone: a healthy
        link loses as many with a probability below ``alpha`` (``observer.loss_tail``)."""
        return loss_tail(lost, sent, self.comms.packet_loss, self.burst) <= self.alpha

    def _loss(self, sc: int, obs: ObserverState, images: list[PoiObservations], b: float
              ) -> tuple[int, list[FaultReport]]:
        if not images:
            return 0, []
        seqs = sorted(m.seq for m in images)
        if obs.resync:  # the numbers the store lost were declared as its overflow
            obs.last_seq, obs.resync = max(obs.last_seq, seqs[0] - 1), False
        lost = obs.count_observations(seqs)
        if obs.link_declared:  # the gap is the silence already declared: count afresh
            self.loss.update(sc, False)
            return 0, []
        sent = lost + len(seqs)
        fraction, limit = lost / sent, self.limit(sent)
        declared = self.loss.declared(sc)
        persisted = self.loss.update(sc, fraction > limit)
        alone = fraction > limit and not declared and self.decisive(lost, sent)
        if not (persisted or alone):
            return lost, []
        self.loss.declare(sc)
        return lost, [self._loss_report(sc, fraction, limit, b)]

    def _loss_report(self, sc: int, fraction: float, limit: float, b: float) -> FaultReport:
        self.log.warning("FDIR: sc%d lost %.0f%% of its observations: link fault", sc,
                         100.0 * fraction)
        return FaultReport(sender=self.node, t_sim=b, spacecraft=sc, fault_class="link",
                           metric=fraction, threshold=limit, window_end_s=b)

    def pass_silence(self, sc: int, obs: ObserverState, t: float) -> list[FaultReport]:
        """Observer ``sc``, of which nothing came down in the pass in progress by ``t`` (s)
        while others were heard (the caller's judgement): a link fault, once per episode."""
        if obs.link_declared or obs.dump_declared:
            return []
        obs.link_declared, obs.silent = True, max(obs.silent, 1)
        self.log.warning("FDIR: nothing of sc%d came down in the pass by %.0f s: link fault",
                         sc, t)
        return [FaultReport(sender=self.node, t_sim=t, spacecraft=sc, fault_class="link",
                            window_end_s=t)]

    def dump(self, sc: int, obs: ObserverState, store: StoreCounter, t: float
             ) -> list[FaultReport]:
        """Observer ``sc``'s ``store`` accounting as it came down at ``t`` (s): once
        ``rates.fdi_period_s`` has passed since the last look, the share of its transmissions
        lost (sent again) against the link's limit; returns the link fault declared (module
        docstring)."""
        start = obs.dump_start
        if start is None or store.dumped < start[1]:
            obs.dump_start = (t, store.dumped, store.retransmitted)
            return []
        if t - start[0] < self.period_s - TIME_TOL_S:
            return []
        obs.dump_start = (t, store.dumped, store.retransmitted)
        lost = store.retransmitted - start[2]
        sent = lost + store.dumped - start[1]
        if sent <= 0:
            return []
        fraction, limit = lost / sent, self.limit(sent)
        if fraction <= limit:
            obs.dump_declared = False
            return []
        if obs.dump_declared or obs.link_declared or not self.decisive(lost, sent):
            return []
        obs.dump_declared = True
        self.log.warning("FDIR: sc%d's dump lost %.0f%% of %d transmissions: link fault", sc,
                         100.0 * fraction, sent)
        return [FaultReport(sender=self.node, t_sim=t, spacecraft=sc, fault_class="link",
                            metric=fraction, threshold=limit, window_end_s=t)]

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

    def _gap(self, sc: int, obs: ObserverState, images: list[PoiObservations],
             b: float) -> list[FaultReport]:
        """A silence that no whole window holds, ended by this window's images: no image sent
        (by the messages' own times: a rejoining node sends the images it recovers late) for
        as long as a window, since the last one judged or between two of this window's;
        decided as a silent window would be (alone when decisive, else ``silent_windows``
        windows' time).  None when the link fault was declared already (a silent window, a
        loss, a dump's loss: one link fault, declared once)."""
        if obs.link_declared or obs.dump_declared or self.loss.declared(sc):
            return []
        sent = sorted([*([] if obs.last_image_s is None else [obs.last_image_s]),
                       *(m.t_sim for m in images)])
        if len(sent) < 2:
            return []
        silent_s, since = max((t1 - t0, t0) for t0, t1 in pairwise(sent))
        n = self.images_per_window
        need_s = self.period_s * (1 if self.decisive(n, n) else self.cfg.silent_windows)
        if silent_s < need_s - TIME_TOL_S:
            return []
        self.log.warning("FDIR: sc%d sent no image for %.1f s (%.1f to %.1f s): link fault",
                         sc, silent_s, since, since + silent_s)
        return [FaultReport(sender=self.node, t_sim=b, spacecraft=sc, fault_class="link",
                            metric=silent_s, threshold=need_s, window_end_s=b)]

    def _silence(self, sc: int, obs: ObserverState, b: float) -> list[FaultReport]:
        obs.silent += 1
        if self.loss.declared(sc):  # the loss that went silent is the link fault declared
            obs.link_declared = True
        n = self.images_per_window
        if obs.link_declared or obs.dump_declared or (obs.silent < self.cfg.silent_windows
                                                      and not self.decisive(n, n)):
            return []
        obs.link_declared = True
        self.log.warning("FDIR: sc%d silent for %d windows: link fault", sc, obs.silent)
        return [FaultReport(sender=self.node, t_sim=b, spacecraft=sc, fault_class="link",
                            window_end_s=b)]
