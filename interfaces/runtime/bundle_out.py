"""A process's outgoing bundle (``interfaces.contracts.bundle``): the hardware traffic its
Buses publish during a tick, held and sent as one message when the process's tick ends.

Every Bus of the process shares it (``Bus.bundle``): a message on a ``bundled`` topic is
numbered, stamped, kept for resend requests and delivered to its own node's subscribers by its
Bus as any other, then handed here instead of to the transport.  Whoever ends the process's
tick (the sim after the tick it publishes, a fleet or a lone executive after its answers)
calls :meth:`BundleOut.flush`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from interfaces.contracts.bundle import bundle_key
from interfaces.runtime.transport import Sample, Transport


class Member(Protocol):
    """What sharing a bundle needs of a Bus (no import of the Bus, which imports this)."""

    node: str
    transport: Transport
    bundle: BundleOut | None


@dataclass(eq=False)
class BundleOut:
    """The bundle of the process publishing on ``key`` through ``transport`` (module
    docstring)."""

    key: str
    transport: Transport
    rows: list[Sample] = field(default_factory=list)
    sent: int = 0
    """Bundles sent."""

    @classmethod
    def share(cls, buses: Sequence[Member], mission: str) -> BundleOut:
        """One bundle for the nodes of one process (``buses``), sent on the first one's
        transport, given to each of them."""
        bundle = cls(bundle_key(mission, [b.node for b in buses]), buses[0].transport)
        for bus in buses:
            bus.bundle = bundle
        return bundle

    def add(self, sample: Sample) -> None:
        self.rows.append(sample)

    def flush(self) -> None:
        """Send what is held, as one bundle (nothing when nothing is held)."""
        if self.rows:
            rows, self.rows = self.rows, []
            self.sent += 1
            self.transport.send_bundle(self.key, rows)
