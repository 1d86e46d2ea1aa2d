"""The messages a node sent in its last few ticks, kept to be sent again on request: how a node
that missed what a tick announces (it was restarted from its critical-data store while the
others ran on, or the network went down under it) gets it back without anyone sending twice to
everybody.

A Bus keeps its own samples of the last ``RECENT_TICKS`` ticks (a tick ends when the executive or
the sim takes ``Bus.published_since_last``) and answers the query
``<node prefix>/bus/recent`` (``topics.recent_queryable``) with all of them, as JSON: a list of
``[key, type name, payload]``.  The node that asks feeds the replies through its own receiving
path (validation, admission: what it holds already is a duplicate and dropped), so nothing is
trusted for having been asked for.

Depth: a node restored from its store of tick m (written at its ω_mid boundaries) runs again
the ticks from m+1 to the one the sim holds open for it, k: it needs what the others sent from
tick m on, and the sim's ticks themselves.  No other node is past tick k, so the ticks of one
ω_mid period and a margin are enough (``depth_for``).
"""

from __future__ import annotations

import json
import logging
from collections import deque
from typing import Protocol

from interfaces.contracts import topics
from interfaces.runtime.admission import Admission
from interfaces.runtime.transport import Sample, Transport

RECENT_TICKS = 4
"""Ticks of sent messages kept for a resend request, by default."""
MARGIN_TICKS = 4
"""Ticks kept beyond one ω_mid period (``depth_for``)."""
MAX_REPLY_BYTES = 8 << 20
"""Largest reply taken from another node (a few hundred messages are a few hundred kB)."""


class RecentSent:
    """The samples a node sent in its last ``depth`` ticks and in the current one (module
    docstring)."""

    __slots__ = ("_ticks",)

    def __init__(self, depth: int = RECENT_TICKS) -> None:
        self._ticks: deque[list[Sample]] = deque([[]], maxlen=depth + 1)

    def keep(self, depth: int) -> None:
        """Keep the last ``depth`` ticks (and the current one) from now on."""
        self._ticks = deque(self._ticks, maxlen=depth + 1)

    def add(self, sample: Sample) -> None:
        """A sample sent in the current tick."""
        self._ticks[-1].append(sample)

    def next_tick(self) -> None:
        """The current tick has ended (the oldest kept is forgotten)."""
        self._ticks.append([])

    def checkpoint(self) -> list[list[tuple[str, str, bytes]]]:
        """The kept samples, tick by tick, as (key, type name, payload) for the node's
        critical-data store: restored with the node, it can send them again to the nodes
        restarted with it (``interfaces.runtime.restart.resume_together``)."""
        return [[(s.key, s.type_name, s.payload) for s in tick] for tick in self._ticks]

    def restore(self, saved: list[list[tuple[str, str, bytes]]]) -> None:
        """Take back a :meth:`checkpoint`."""
        self._ticks = deque([[Sample(k, t, payload=p) for k, t, p in tick] for tick in saved],
                            maxlen=self._ticks.maxlen)

    def reply(self, _key: str = "") -> bytes:
        """Every kept sample, oldest first, as the query's JSON reply."""
        return json.dumps([[s.key, s.type_name, s.payload.decode()]
                           for tick in list(self._ticks) for s in list(tick)]).encode()


def depth_for(ticks_per_mid: int) -> int:
    """Ticks to keep so that a node restored from its last ω_mid store can run again every
    tick since (``ticks_per_mid``: ticks in one ω_mid period)."""
    return ticks_per_mid + MARGIN_TICKS


def parse_reply(payload: bytes) -> list[Sample]:
    """The samples of a reply (``RecentSent.reply``); a malformed reply gives ValueError."""
    if len(payload) > MAX_REPLY_BYTES:
        raise ValueError(f"reply of {len(payload)} bytes exceeds {MAX_REPLY_BYTES}")
    rows = json.loads(payload)
    if not isinstance(rows, list) or not all(
            isinstance(r, list) and len(r) == 3 and all(isinstance(x, str) for x in r)
            for r in rows):
        raise ValueError("a reply is a list of [key, type name, payload] strings")
    return [Sample(k, t, payload=p.encode()) for k, t, p in rows]


def fetch(transport: Transport, mission: str, owner: str,
          timeout_s: float = 2.0) -> tuple[list[Sample], list[str]]:
    """What node ``owner`` sent in its last ticks, its own keys only, oldest first; and why
    each malformed reply was set aside (the Bus counts them, the recorder logs them)."""
    samples: list[Sample] = []
    malformed: list[str] = []
    for _key, payload in transport.query(topics.recent_queryable(mission, owner), timeout_s):
        try:
            samples += [s for s in parse_reply(payload) if topics.node_of_key(s.key) == owner]
        except ValueError as e:
            malformed.append(str(e))
    return samples, malformed


class Receiver(Protocol):
    """What asking for the recent ticks needs of a node's Bus."""

    node: str
    mission: str
    transport: Transport
    log: logging.Logger
    admission: Admission

    def take_in(self, sample: Sample) -> int:
        """Receive ``sample`` as if it had just arrived; 1 if it was taken."""

    def drop_invalid(self, key: str, why: str) -> None:
        """Count and log an invalid message on ``key``."""


def fetch_recent(bus: Receiver, owner: str, timeout_s: float = 2.0) -> list[Sample]:
    """What node ``owner`` sent in its last ticks, its own keys only, oldest first, asked by
    ``bus``'s node; a malformed reply is counted there as invalid and skipped."""
    samples, malformed = fetch(bus.transport, bus.mission, owner, timeout_s)
    for why in malformed:
        bus.drop_invalid(topics.recent_queryable(bus.mission, owner), why)
    return samples


def recover(bus: Receiver, keys: list[str], timeout_s: float = 2.0) -> int:
    """Ask the publishers of ``keys`` (announced to ``bus``'s node, not arrived) for what they
    sent in their last ticks, and take it in as if it had just arrived (``take_in``: what is
    held already is a duplicate).  Returns the samples taken in."""
    owners = sorted({o for k in keys if (o := bus.admission.owner(k)) and o != bus.node})
    taken = sum(bus.take_in(s) for o in owners for s in fetch_recent(bus, o, timeout_s))
    if owners:
        bus.log.warning("%s asked %s for %d announced key(s) that never came; %d "
                        "message(s) taken in", bus.node, ", ".join(owners), len(keys), taken)
    return taken
