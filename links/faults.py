"""Link fault injection: a spacecraft's ``link_loss`` cuts every link it has, and its
``packet_loss`` adds an independent loss probability (``magnitude``) on each, both for the
messages sent in [start_s, end_s) (link faults act on send times; the sim's and the software's
switch on ticks, ``faults/schedule.py``).  The receiving node's channel stage
(``links/channel.py``) asks for both on every cross-link message.

A ``packet_loss`` fault draws from a stream of its own per directed link
(``link-fault:<src>-><receiver>``), so the link's nominal loss draws are the same with and
without it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from interfaces.contracts.rng import stream
from interfaces.contracts.scenario import Fault
from interfaces.contracts.topics import sc_node


@dataclass(frozen=True)
class LinkCutWindow:
    """Every link of ``node`` (``"*"``: any other end) cut for the messages sent in
    [start_s, end_s)."""

    node: str
    start_s: float
    end_s: float


@dataclass(eq=False)
class LinkFaults:
    """The link faults of a run as the channel stage of node ``receiver`` sees them."""

    receiver: str
    seed: int
    faults: Sequence[Fault] = ()
    streams: dict[str, np.random.Generator] = field(default_factory=dict)
    """The loss draws' random stream of each source node, made on first use."""

    def __post_init__(self) -> None:
        self._loss = [(sc_node(f.spacecraft), f.start_s, end_s(f), float(f.magnitude or 0.0))
                      for f in self.faults if f.kind == "packet_loss"]

    def cuts(self) -> list[LinkCutWindow]:
        """The ``link_loss`` faults as cuts of every link of their spacecraft."""
        return [LinkCutWindow(sc_node(f.spacecraft), f.start_s, end_s(f))
                for f in self.faults if f.kind == "link_loss"]

    def lost(self, src: str, t_send: float) -> bool:
        """Whether the active ``packet_loss`` faults on the link from ``src`` lose a message
        sent at ``t_send`` (s): each an independent Bernoulli draw from the link's own fault
        stream."""
        lost = False
        for node, start, end, p in self._loss:
            if start <= t_send < end and node in (src, self.receiver):
                rng = self.streams.get(src)
                if rng is None:
                    rng = self.streams[src] = stream(self.seed,
                                                   f"link-fault:{src}->{self.receiver}")
                lost = (rng.random() < p) or lost
        return lost


def end_s(fault: Fault) -> float:
    """When ``fault`` ends (s): never, when the scenario gives no end."""
    return math.inf if fault.end_s is None else fault.end_s
