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

Kept until archived: a node that serves its recent ticks on a run's network
(``Bus.serve_recent``) also keeps every tick the run's recorder has not yet written to its
archive for good.  After each chunk it closes, the recorder tells every node the sim time of the
last tick it holds (a query on ``<node prefix>/bus/archived/<t_ns>``, ``archived_key``); a node
forgets a tick only when the ``ARCHIVE_MARGIN_TICKS`` ticks after it are that old too.  A
recorder killed and restarted, or cut off while the router restarted, therefore finds in the
nodes' replies everything it had not closed in a chunk and everything sent while it could not
hear, however far the sim ran before it held the clock.  What is kept so is bounded
(``MAX_KEPT_BYTES``, so that a reply always fits ``MAX_REPLY_BYTES``): past it the oldest ticks
go all the same, counted in ``RecentSent.forgotten`` (and logged by the Bus), and the archive's
sequence numbers count them lost.
"""

from __future__ import annotations

import json
import logging
from collections import deque
from typing import NamedTuple, Protocol

from interfaces.contracts import topics
from interfaces.runtime.admission import Admission
from interfaces.runtime.transport import Sample, Transport

RECENT_TICKS = 4
"""Ticks of sent messages kept for a resend request, by default."""
MARGIN_TICKS = 4
"""Ticks kept beyond one ω_mid period (``depth_for``)."""
MAX_REPLY_BYTES = 8 << 20
"""Largest reply taken from another node (a few hundred messages are a few hundred kB)."""
MAX_KEPT_BYTES = MAX_REPLY_BYTES // 4
"""Payload bytes kept beyond the last ticks for a recorder that has not archived them (each
payload travels as a JSON string in the reply: its quotes escaped, it may grow)."""
ARCHIVE_MARGIN_TICKS = 2
"""Ticks after a tick that must be archived too before that tick is forgotten: a message of an
archived time may still be on its way to the recorder through another router."""


class _Tick:
    """The samples a node sent in one tick; once the tick has ended, the latest sim time they
    carry (``t_ns``, ns; -1 for none) and their payload bytes (``size``, counted only while
    ticks are kept until archived)."""

    __slots__ = ("samples", "t_ns", "size")

    def __init__(self, samples: list[Sample] | None = None) -> None:
        self.samples: list[Sample] = [] if samples is None else samples
        self.t_ns = -1
        self.size = 0

    def close(self, until_archived: bool) -> None:
        """The tick has ended: with ``until_archived`` (the only use of both), its latest sim
        time and its size; nothing otherwise (a tick of every node in every run: no work)."""
        if until_archived:
            self.t_ns = max((_t_ns(s) for s in self.samples), default=-1)
            self.size = sum(len(s.payload) for s in self.samples)


def _t_ns(sample: Sample) -> int:
    """A sample's sim time, ns (-1 when it has none)."""
    msg = sample.message
    if msg is not None:
        return round(msg.t_sim * 1e9)
    try:
        t = json.loads(sample.payload).get("t_sim")
    except (ValueError, AttributeError):
        return -1
    return round(t * 1e9) if type(t) in (int, float) and 0.0 <= t < 9.2e9 else -1


class RecentSent:
    """The samples a node sent in its last ``depth`` ticks and in the current one, and those
    the recorder has not archived yet, up to ``max_bytes`` (module docstring).

    Threads: the node adds and ends ticks on its own thread; ``reply`` and ``archived`` answer
    queries on transport threads."""

    __slots__ = ("_ticks", "_depth", "_max_bytes", "_size", "_until_archived", "_archived_ns",
                 "forgotten")

    def __init__(self, depth: int = RECENT_TICKS, max_bytes: int = MAX_KEPT_BYTES) -> None:
        self._ticks: deque[_Tick] = deque([_Tick()])
        self._depth, self._max_bytes = depth, max_bytes
        self._size = 0
        """Payload bytes of the ended ticks kept."""
        self._until_archived = False
        self._archived_ns = -1
        """The sim time of the last tick the recorder archived for good, ns (-1: none yet)."""
        self.forgotten = 0
        """Samples forgotten before the recorder said it archived them (``max_bytes``)."""

    def keep(self, depth: int) -> None:
        """Keep the last ``depth`` ticks (and the current one) from now on."""
        self._depth = depth
        self._trim()

    def keep_until_archived(self) -> None:
        """Keep from now on what the run's recorder has not archived too."""
        self._until_archived = True

    def add(self, sample: Sample) -> None:
        """A sample sent in the current tick (none kept at depth 0: in one process nothing
        can ask for a resend)."""
        if self._depth or self._until_archived:
            self._ticks[-1].samples.append(sample)

    def next_tick(self) -> None:
        """The current tick has ended: what is no longer needed is forgotten."""
        if not (self._depth or self._until_archived):
            return  # depth 0: nothing was kept
        ended = self._ticks[-1]
        ended.close(self._until_archived)
        self._size += ended.size
        self._ticks.append(_Tick())
        self._trim()

    def last_tick(self) -> list[Sample]:
        """The samples of the last tick that has ended (none before the first)."""
        return list(self._ticks[-2].samples) if len(self._ticks) > 1 else []

    def archived(self, key: str) -> None:
        """Query responder of ``archived_key``: the recorder archived every tick up to the
        sim time its last segment names (ns).  Nothing is replied."""
        t_ns = key.rsplit("/", 1)[-1]
        if t_ns.isdigit() and len(t_ns) <= 19:
            self._archived_ns = max(self._archived_ns, int(t_ns))

    def _trim(self) -> None:
        """Forget the oldest ticks beyond the last ``depth``, unless the recorder still needs
        them (not archived, ``ARCHIVE_MARGIN_TICKS``) and they fit in ``max_bytes``."""
        ticks = self._ticks
        while len(ticks) > self._depth + 1:
            oldest = ticks[0]
            if self._until_archived and not self._is_archived():
                if self._size <= self._max_bytes:
                    return
                self.forgotten += len(oldest.samples)
            ticks.popleft()
            self._size -= oldest.size

    def _is_archived(self) -> bool:
        """Whether the recorder archived the oldest tick and the margin after it."""
        ticks = self._ticks
        return ticks[min(ARCHIVE_MARGIN_TICKS, len(ticks) - 2)].t_ns < self._archived_ns

    def checkpoint(self) -> list[list[tuple[str, str, bytes]]]:
        """The kept samples, tick by tick, as (key, type name, payload) for the node's
        critical-data store: restored with the node, it can send them again to the nodes
        restarted with it (``interfaces.runtime.restart.resume_together``)."""
        return [[(s.key, s.type_name, s.payload) for s in tick.samples] for tick in self._ticks]

    def restore(self, saved: list[list[tuple[str, str, bytes]]]) -> None:
        """Take back a :meth:`checkpoint` (what the recorder archived is asked again)."""
        ticks = [_Tick([Sample(k, t, payload=p) for k, t, p in tick]) for tick in saved]
        for tick in ticks[:-1]:
            tick.close(self._until_archived)
        self._ticks = deque(ticks or [_Tick()])
        self._size = sum(t.size for t in self._ticks)

    def reply(self, _key: str = "") -> bytes:
        """Every kept sample, oldest first, as the query's JSON reply."""
        return json.dumps([[s.key, s.type_name, s.payload.decode()]
                           for tick in list(self._ticks) for s in list(tick.samples)]).encode()


def archived_key(mission: str, node: str, t_ns: int) -> str:
    """The query by which the recorder tells ``node`` it archived every tick up to sim time
    ``t_ns`` (ns) (``RecentSent.archived``)."""
    return f"{topics.node_prefix(mission, node)}/bus/archived/{t_ns}"


def archived_queryable(mission: str, node: str) -> str:
    """The key expression ``node`` answers ``archived_key`` queries on."""
    return f"{topics.node_prefix(mission, node)}/bus/archived/*"


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


class Fetched(NamedTuple):
    """What a node answered: the samples it kept, its own keys only, oldest first; why each
    malformed reply was set aside (the Bus counts them, the recorder logs them); whether it
    answered at all (it is not on the network, or not yet back on it)."""

    samples: list[Sample]
    malformed: list[str]
    answered: bool


def fetch(transport: Transport, mission: str, owner: str, timeout_s: float = 2.0) -> Fetched:
    """What node ``owner`` sent in its last ticks (and kept for the recorder)."""
    samples: list[Sample] = []
    malformed: list[str] = []
    replies = transport.query(topics.recent_queryable(mission, owner), timeout_s)
    for _key, payload in replies:
        try:
            samples += [s for s in parse_reply(payload) if topics.node_of_key(s.key) == owner]
        except ValueError as e:
            malformed.append(str(e))
    return Fetched(samples, malformed, bool(replies))


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
    samples, malformed, _ = fetch(bus.transport, bus.mission, owner, timeout_s)
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
