"""The link stage as the Bus sees it: what a message between two nodes crosses on its way from
sender to receivers (docs/architecture.md, "The channel stage").  The runtime declares it; the
simulated radio (``links/``: range, loss, delay, cuts, ground passes and onboard stores)
implements it, and the process that builds a node hands one to its Bus.  So the runtime knows
that a link stage exists, never how a radio works.

The Bus asks the stage about every message from another spacecraft or ground node
(:func:`crosses_link`), in delivery order (send time, key, sequence), so what it decides does not
depend on the transport or on arrival order.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal, Protocol

from interfaces.contracts.messages import LinkCounter, Message, TruthState
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topics import GROUND, spacecraft_of

Transmission = Literal["deliver", "drop", "wait"]
"""What the stage made of one message: delivered now; dropped (counted on its link); or taken
to wait on the link (a ground pass, an onboard store), to come back from ``released``."""


class LinkStage(Protocol):
    """The links into one receiving node."""

    @property
    def delay_s(self) -> float:
        """The links' fixed delay, s: a message is due no earlier than its send time plus it."""

    def truth_feed(self) -> Callable[[TruthState], None] | None:
        """The handler of the sim's truth that the first Bus of a process subscribes (the
        positions its ranges are judged on, shared by the nodes of the process); None for
        every later caller."""

    def transmit(self, src: str, key: str, msg: Message, envelope: Any) -> Transmission:
        """Judge one message from node ``src`` on ``key`` (counted on its link); a message
        that must wait is kept with its ``envelope``."""

    def released(self, t_now: float) -> list[Any]:
        """The envelopes that waited (``transmit`` gave ``"wait"``) and reach the receiver by
        ``t_now`` (s), in delivery order."""

    def counters(self) -> list[LinkCounter]:
        """Copies of the per-link counters, sorted by source."""

    def checkpoint(self, since_s: float, pack: Callable[[Any], Any]) -> dict[str, Any]:
        """What the stage learnt while running, for the node's critical-data store: the
        truth it judges ranges on from ``since_s`` (s) on, and the envelopes waiting, each as
        ``pack(envelope)``."""

    def restore(self, saved: dict[str, Any], unpack: Callable[[Any], Any]) -> None:
        """Take back a ``checkpoint``, each waiting envelope as ``unpack(packed)``."""


LinkStageFactory = Callable[[str, Scenario], LinkStage]
"""Builds the link stage of receiving node ``node`` in a run of ``scenario``."""


def crosses_link(src: str | None, dst: str) -> bool:
    """Whether a message from node ``src`` to node ``dst`` crosses a modelled link: between two
    different nodes that are each a spacecraft or the ground (sim traffic is hardware-internal)."""
    if src is None or src == dst:
        return False
    return all(n == GROUND or spacecraft_of(n) is not None for n in (src, dst))
