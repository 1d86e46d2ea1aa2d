"""Channel model of the links between spacecraft and between spacecraft and ground.

Applied by the receiving node's Bus to every message from another spacecraft/ground node, in a
deterministic order (sorted by send time, key, sequence), so results do not depend on the
transport or on arrival order:

* range: delivered only when the two ends are within ``comms.range_m`` at the *send* time, using
  the sim's truth positions (LVLH, m).  The ground is reached through the target, at the origin.
* cuts: scheduled link cuts (``comms.cuts``), ``link_loss`` faults (every link of the faulty
  spacecraft: ``links/faults.py``) and injected ones (``cut``) drop everything.
* loss: Bernoulli with ``comms.packet_loss``, or Gilbert-Elliott bursts with the same mean loss
  rate and a mean burst length ``comms.burst.mean_length_packets`` (Gilbert 1960, Elliott 1963:
  two-state Markov chain, loss in the bad state).  Every directed link has its own generator
  seeded from the scenario seed and the link name.  A ``packet_loss`` fault adds an independent
  Bernoulli loss (its ``magnitude``) on every link of its spacecraft, from a separate stream
  (``links/faults.py``).
* delay: a fixed ``comms.delay_s``; the Bus holds a message until the receiver's time reaches
  send time + delay (and at least one tick).

The channel is a stage of its own between sender and receivers: it is the link stage the
runtime declares (``interfaces.runtime.link_stage``), and the receiving Bus asks its
``transmit`` for every cross-link message, in delivery order.  The truth it reads is a
:class:`links.truth.TruthHistory`, one per process.  With ground passes, what waits on the
space-ground links is the ``SpaceGroundLink``'s (``links.space_ground``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import InitVar, dataclass, field
from enum import Enum
from typing import Any, Literal

import numpy as np

from gnc.passes import ContactPlan
from interfaces.contracts.messages import LinkCounter, Message, TruthState
from interfaces.contracts.rng import stream
from interfaces.contracts.scenario import Comms, Fault, Ground, LinkCut, Scenario
from links.faults import LinkFaults
from links.space_ground import SpaceGroundLink
from links.truth import TruthHistory, history_for


class Verdict(Enum):
    DELIVER = "delivered"
    RANGE = "dropped_range"
    LOSS = "dropped_loss"
    CUT = "dropped_cut"


def gilbert_elliott_rates(loss_rate: float, mean_burst_packets: float) -> tuple[float, float]:
    """Transition probabilities (good→bad p, bad→good r) of a Gilbert channel whose stationary
    loss rate is ``loss_rate`` = p/(p+r) and whose mean loss-burst length is 1/r packets."""
    if not 0.0 <= loss_rate < 1.0:
        raise ValueError(f"loss rate must be in [0, 1), got {loss_rate}")
    if mean_burst_packets < 1.0:
        raise ValueError(f"mean burst length must be >= 1 packet, got {mean_burst_packets}")
    r = 1.0 / mean_burst_packets
    p = r * loss_rate / (1.0 - loss_rate)
    if p > 1.0:
        raise ValueError(
            f"loss rate {loss_rate} with bursts of {mean_burst_packets} packets is not realizable "
            f"(needs P(good→bad) = {p:.3f} > 1)"
        )
    return p, r


@dataclass
class _Link:
    rng: np.random.Generator
    counter: LinkCounter
    bad: bool = False


@dataclass
class _Cut:
    a: str
    b: str
    start_s: float
    end_s: float

    def covers(self, src: str, dst: str, t: float) -> bool:
        if not self.start_s <= t < self.end_s:
            return False
        return (_end_matches(self.a, src) and _end_matches(self.b, dst)) or (
            _end_matches(self.a, dst) and _end_matches(self.b, src)
        )


def _end_matches(pattern: str, node: str) -> bool:
    return pattern == "*" or pattern == node


@dataclass
class ChannelModel:
    """The channel as seen by one receiving node (``receiver``: "sc<N>" or "ground")."""

    receiver: str
    comms: Comms
    seed: int
    faults: Sequence[Fault] = ()
    """The scenario's faults: ``link_loss`` cuts every link of its spacecraft, ``packet_loss``
    adds a loss probability (``magnitude``) on them, each over [start_s, end_s)."""
    truth: TruthHistory = field(default_factory=TruthHistory)
    """Where the true positions come from (shared by the channel models of one process)."""
    ground: Ground = field(default_factory=Ground)
    """How the ground hears: with ``contact = "passes"``, the space-ground links wait for the
    contact windows (``links.space_ground``)."""
    _links: dict[str, _Link] = field(default_factory=dict)
    _cuts: list[_Cut] = field(default_factory=list)
    contact: InitVar[ContactPlan | None] = None
    """The ground's contact windows (None: it hears continuously)."""

    @classmethod
    def of(cls, receiver: str, scenario: Scenario,
           truth: TruthHistory | None = None) -> ChannelModel:
        """The channel model of ``receiver`` in a run of ``scenario`` (every run, transport
        and replay builds it this way, so its draws are the same), reading ``truth`` (shared
        by the nodes of one process; a history of its own by default)."""
        return cls(receiver, scenario.comms, scenario.seed, scenario.faults,
                   truth if truth is not None else history_for(scenario), scenario.ground,
                   contact=ContactPlan.of(scenario))

    def __post_init__(self, contact: ContactPlan | None) -> None:
        self.passes = (SpaceGroundLink(self.receiver, contact, self.ground, self.comms.delay_s)
                       if contact is not None else None)
        """What waits on the space-ground links (None: the ground hears continuously)."""
        self._cuts = [_Cut(c.a, c.b, c.start_s, c.end_s) for c in self.comms.cuts]
        self._faults = LinkFaults(self.receiver, self.seed, self.faults)
        self._cuts += [_Cut(c.node, "*", c.start_s, c.end_s) for c in self._faults.cuts()]
        self._ge = (
            gilbert_elliott_rates(self.comms.packet_loss, self.comms.burst.mean_length_packets)
            if self.comms.burst is not None and self.comms.packet_loss > 0.0
            else None
        )

    @property
    def delay_s(self) -> float:
        """The links' fixed delay, s (``comms.delay_s``)."""
        return self.comms.delay_s

    @property
    def plan(self) -> ContactPlan | None:
        """The ground's contact windows (None: it hears continuously)."""
        return None if self.passes is None else self.passes.plan

    # --- inputs --------------------------------------------------------------------------

    def truth_feed(self) -> Callable[[TruthState], None] | None:
        """The handler of the sim's truth for the first Bus of the process to ask (its truth
        history is shared by the process's channel models); None for the others."""
        return self.truth.observe if self.truth.claim_feed() else None

    def cut(self, a: str, b: str = "*", start_s: float = 0.0, end_s: float = math.inf) -> None:
        """Inject a link cut (e.g. a ``link_loss`` fault)."""
        LinkCut(a=a, b=b, start_s=start_s, end_s=end_s)  # validates the ends
        self._cuts.append(_Cut(a, b, start_s, end_s))

    # --- decision ------------------------------------------------------------------------

    def transmit(self, src: str, key: str, msg: Message,
                 envelope: object) -> Literal["deliver", "drop", "wait"]:
        """One message from ``src`` on ``key`` (the runtime's link stage): with ground passes
        one that must wait on a space-ground link (stored onboard, or held on the ground until
        a pass) is taken, to come back from ``released``, and what the ground loaded before the
        run is delivered (``SpaceGroundLink.preloaded``); any other is judged now (``decide``,
        counted)."""
        if self.passes is not None and self.passes.preloaded(src, msg):
            link = self._link(src)
            link.counter.sent += 1
            link.counter.delivered += 1
            return "deliver"
        if self.passes is not None and self.passes.takes(src, key, msg, envelope):
            return "wait"
        return "deliver" if self.delivers(src, msg.t_sim) else "drop"

    def decide(self, src: str, t_send: float) -> Verdict:
        """Fate of one message from ``src`` sent at ``t_send``; updates the link counters.

        Call in a deterministic order (the Bus sorts by send time, key, sequence)."""
        link = self._link(src)
        blocked = self._blocked(src, t_send)
        if blocked is None:
            return Verdict.LOSS if self.lose(src, t_send) else Verdict.DELIVER
        link.counter.sent += 1
        if blocked is Verdict.RANGE:
            link.counter.dropped_range += 1
        else:
            link.counter.dropped_cut += 1
        return blocked

    def delivers(self, src: str, t_send: float) -> bool:
        """Whether ``decide`` delivers the message."""
        return self.decide(src, t_send) is Verdict.DELIVER

    def link_up(self, src: str, t_s: float) -> bool:
        """Whether the link from ``src`` is up at ``t_s`` (s): not cut, and in range."""
        return self._blocked(src, t_s) is None

    def lose(self, src: str, t_s: float) -> bool:
        """One transmission from ``src`` at ``t_s`` (s) on a link that is up: whether it is
        lost (drawn once from the link's stream), counted on the link as sent and as lost or
        delivered."""
        link = self._link(src)
        link.counter.sent += 1
        lost = self._lost(link, src, t_s)
        if lost:
            link.counter.dropped_loss += 1
        else:
            link.counter.delivered += 1
        return lost

    def released(self, t_now: float) -> list[Any]:
        """The envelopes taken (``transmit`` gave ``"wait"``) that reach the receiver by
        ``t_now`` (s), in order."""
        return [] if self.passes is None else self.passes.released(t_now, self)

    def _blocked(self, src: str, t: float) -> Verdict | None:
        """CUT or RANGE when the link from ``src`` is down at ``t`` (s), else None."""
        if any(c.covers(src, self.receiver, t) for c in self._cuts):
            return Verdict.CUT
        if not self._in_range(src, t):
            return Verdict.RANGE
        return None

    def _lost(self, link: _Link, src: str, t: float) -> bool:
        """Whether one packet on the link, in range and not cut, is lost.  It draws exactly
        once from its link's stream; cut and out-of-range messages draw nothing (the
        Gilbert-Elliott state advances per packet sent)."""
        lost = False
        if self._ge is not None:
            p, r = self._ge
            u = link.rng.random()
            link.bad = (u >= r) if link.bad else (u < p)
            lost = link.bad
        elif self.comms.packet_loss > 0.0:
            lost = link.rng.random() < self.comms.packet_loss
        return lost or self._faults.lost(src, t)

    def _in_range(self, src: str, t_send: float) -> bool:
        pos = self.truth.positions_at(t_send)
        if pos is None:
            return False
        a, b = pos.get(src), pos.get(self.receiver)
        if a is None or b is None:
            return False
        return float(np.linalg.norm(a - b)) <= self.comms.range_m

    def _link(self, src: str) -> _Link:
        link = self._links.get(src)
        if link is None:
            rng = stream(self.seed, f"link:{src}->{self.receiver}")
            link = _Link(rng, LinkCounter(src=src, dst=self.receiver))
            self._links[src] = link
        return link

    # --- restarts ------------------------------------------------------------------------

    def checkpoint(self, since_s: float, pack: Callable[[Any], Any]) -> dict[str, Any]:
        """What this model learnt while running (each link's random stream, burst state and
        counters, the cuts, the link-fault streams, the truth history from ``since_s`` on, and
        what waits on the space-ground links, each envelope as ``pack(envelope)``), for a
        node's critical-data store; the values are the model's own (pickle them at once)."""
        return {"links": self._links, "cuts": self._cuts,
                "fault_streams": self._faults.streams, "truth": self.truth.checkpoint(since_s),
                "passes": None if self.passes is None else self.passes.with_envelopes(pack)}

    def restore(self, saved: dict[str, Any], unpack: Callable[[Any], Any]) -> None:
        """Take back a ``checkpoint``, each waiting envelope as ``unpack(packed)``."""
        self._links, self._cuts = saved["links"], saved["cuts"]
        self._faults.streams = saved["fault_streams"]
        self.truth.restore(saved["truth"])
        if saved["passes"] is not None:
            self.passes = saved["passes"].with_envelopes(unpack)

    def counters(self) -> list[LinkCounter]:
        """Copies of the per-link counters, sorted by source."""
        if self.passes is not None:
            for src in self.passes.stores:  # a store not yet dumped from has its link too
                self._link(src)
        copies = [self._links[s].counter.model_copy() for s in sorted(self._links)]
        if self.passes is None:
            return copies
        return [self.passes.annotate(c) for c in copies]
