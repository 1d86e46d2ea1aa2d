"""A spacecraft's onboard store of its telemetry to the ground, and its dump in the passes
(``[ground] contact = "passes"``; docs/architecture.md, "Ground passes").

Every message a spacecraft sends the ground enters its store at its send time.  The rules:

* **Priority** (``catalogue.downlink_priority``): 0, the FDIR's events and decisive telemetry;
  1, the rest of what the ground FDIR judges (nav, attitude, images); 2, housekeeping.
* **Bounded** at ``capacity_bytes``.  A message that does not fit evicts the oldest messages
  of the lowest priority below its own, as many as it needs; when even that would not make
  room it is refused and nothing is evicted.  Both are overflow: counted, logged, and kept as
  runs of one topic and their send times (``OverflowRun``).
* **Dump.** While the link is up (a station sees the target, the link is not cut, the
  spacecraft is within range of the target: the caller's ``Downlink``), the store is sent at
  ``rate_bps``, highest priority first and oldest first within one.  Each transmission draws
  the link's loss once; a lost one is sent again, first.  A message reaches the ground when
  its last bit does (plus the link's delay, which the caller adds).  Out of contact the radio
  waits for the next acquisition; in contact with the link down it tries every ``RETRY_S``.
* **Time.** The store is simulated in send time, event by event, up to a ``horizon`` the
  caller gives: every message sent before it has been offered.  So what it delivers, and
  when, depends only on the messages, never on when it is asked.

Sizes are the messages' JSON bytes without the wall-clock stamp (``message_bytes``): the same
for a message made in the process and for one that came over Zenoh.
"""

from __future__ import annotations

import bisect
import dataclasses
import logging
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from interfaces.contracts.messages import Message, OverflowRun, StoreCounter

RETRY_S = 1.0
"""In a pass with the link down (cut, out of range), the radio tries again this often, s."""
PRIORITIES = 3
JUDGED_PRIORITIES = 2
"""Priorities below this carry what the ground FDIR judges (``catalogue.downlink_priority``)."""


def message_bytes(msg: Message) -> int:
    """A message's size in the store and on the downlink: its JSON bytes, wall-clock fields
    left out (they differ between runs; the size must not)."""
    return len(msg.model_dump_json(exclude=set(msg.WALL_CLOCK_FIELDS)))


class Downlink(Protocol):
    """The link a store is dumped on, as the channel stage sees it."""

    def up(self, t_s: float) -> bool:
        """Whether a transmission can start at ``t_s``: in contact, not cut, in range."""

    def lost(self, t_s: float) -> bool:
        """One transmission's fate (draws the link's loss)."""

    def next_contact(self, t_s: float) -> float:
        """``t_s`` in contact, else the next acquisition (inf: none)."""


@dataclass
class _Item:
    env: Any
    """what the caller gets back when the message is dumped (its envelope)"""
    order: tuple[float, str, int]
    size: int
    priority: int
    topic: str

    @property
    def t(self) -> float:
        return self.order[0]


@dataclass(eq=False)
class OnboardStore:
    """The store of spacecraft ``src`` (module docstring)."""

    src: str
    capacity_bytes: int
    rate_bps: float
    log: logging.Logger = field(default_factory=lambda: logging.getLogger("insp.store"))
    counter: StoreCounter = field(default_factory=StoreCounter)
    _arrivals: list[_Item] = field(default_factory=list)
    """offered, sent after the store's clock: not yet entered (by delivery order)"""
    _queues: list[deque[_Item]] = field(
        default_factory=lambda: [deque() for _ in range(PRIORITIES)])
    _bytes: list[int] = field(default_factory=lambda: [0] * PRIORITIES)
    _inflight: tuple[_Item, float, bool] | None = None
    """the message on the air, the time its last bit arrives (s), whether it is lost"""
    _clock_s: float = -math.inf
    """when the radio is free, or tries next (s)"""
    _runs: dict[str, int] = field(default_factory=dict)
    """each topic's last overflow run (index into ``counter.overflow_runs``)"""

    def offer(self, env: Any, msg: Message, topic: str, priority: int) -> None:
        """A message sent to the ground (it enters the store at its send time)."""
        item = _Item(env, (msg.t_sim, topic, msg.seq), message_bytes(msg), priority, topic)
        bisect.insort(self._arrivals, item, key=lambda i: i.order)

    def advance(self, horizon_s: float, link: Downlink) -> list[tuple[float, Any]]:
        """Run the store up to ``horizon_s`` (s, exclusive: every message sent before it has
        been offered); return the messages dumped, each with the time its last bit arrived,
        in that order."""
        out: list[tuple[float, Any]] = []
        while True:
            t_in = self._arrivals[0].t if self._arrivals else math.inf
            t_air = self._next_air_event()
            if min(t_in, t_air) >= horizon_s:
                break
            if t_in <= t_air:
                self._enter(self._arrivals.pop(0))
            elif self._inflight is not None:
                self._land(out)
            else:
                self._transmit(link)
        self._count_onboard()
        return out

    # --- the events -----------------------------------------------------------------------

    def _next_air_event(self) -> float:
        if self._inflight is not None:
            return self._inflight[1]
        return self._clock_s if any(self._bytes) else math.inf

    def _enter(self, item: _Item) -> None:
        c = self.counter
        if self._inflight is None and not any(self._bytes):
            self._clock_s = max(self._clock_s, item.t)
        by_topic = c.offered_bytes_by_topic
        by_topic[item.topic] = by_topic.get(item.topic, 0) + item.size
        used = sum(self._bytes) + (self._inflight[0].size if self._inflight else 0)
        lower = sum(self._bytes[item.priority + 1:])
        if used - lower + item.size > self.capacity_bytes:
            self._overflow(item)
            return
        for p in range(PRIORITIES - 1, item.priority, -1):
            while used + item.size > self.capacity_bytes and self._queues[p]:
                old = self._queues[p].popleft()
                self._bytes[p] -= old.size
                used -= old.size
                self._overflow(old)
        self._queues[item.priority].append(item)
        self._bytes[item.priority] += item.size
        c.stored += 1
        c.stored_bytes += item.size
        c.peak_bytes = max(c.peak_bytes, used + item.size)

    def _transmit(self, link: Downlink) -> None:
        t = self._clock_s
        if not link.up(t):
            nxt = link.next_contact(t)
            self._clock_s = nxt if nxt > t else t + RETRY_S
            return
        p = next(p for p in range(PRIORITIES) if self._queues[p])
        item = self._queues[p].popleft()
        self._bytes[p] -= item.size
        self._inflight = (item, t + item.size * 8.0 / self.rate_bps, link.lost(t))

    def _land(self, out: list[tuple[float, Any]]) -> None:
        assert self._inflight is not None
        item, t, lost = self._inflight
        self._inflight, self._clock_s = None, t
        if lost:  # sent again, first
            self._queues[item.priority].appendleft(item)
            self._bytes[item.priority] += item.size
            self.counter.retransmitted += 1
            return
        self.counter.dumped += 1
        self.counter.dumped_bytes += item.size
        out.append((t, item.env))

    # --- accounting -----------------------------------------------------------------------

    def _overflow(self, item: _Item) -> None:
        c = self.counter
        c.overflow += 1
        c.overflow_bytes += item.size
        i = self._runs.get(item.topic)
        run = c.overflow_runs[i] if i is not None else None
        if run is not None and item.t - run.last_s <= OverflowRun.MERGE_GAP_S:
            run.first_s, run.last_s = min(run.first_s, item.t), max(run.last_s, item.t)
            run.count += 1
            return
        self._runs[item.topic] = len(c.overflow_runs)
        c.overflow_runs.append(OverflowRun(topic=item.topic, first_s=item.t, last_s=item.t,
                                           count=1))
        self.log.warning("%s's store is full (%d bytes): %s lost from t = %.1f s (%d messages "
                         "lost so far)", self.src, self.capacity_bytes, item.topic, item.t,
                         c.overflow)

    def _count_onboard(self) -> None:
        c = self.counter
        flying = [self._inflight[0]] if self._inflight is not None else []
        c.onboard = sum(len(q) for q in self._queues) + len(flying)
        c.onboard_bytes = sum(self._bytes) + sum(i.size for i in flying)
        # each queue holds its messages in send order (a lost one goes back to its front), so
        # the oldest aboard is a queue's head or the one on the air: O(1) per call, every tick
        c.onboard_since_s = self._oldest(PRIORITIES, flying)
        c.judged_since_s = self._oldest(JUDGED_PRIORITIES, flying)

    def _oldest(self, priorities: int, flying: list[_Item]) -> float | None:
        """Send time of the oldest message aboard of priority below ``priorities`` (s)."""
        return min([*(q[0].t for q in self._queues[:priorities] if q),
                    *(i.t for i in flying if i.priority < priorities)], default=None)

    def with_envelopes(self, fn: Callable[[Any], Any]) -> OnboardStore:
        """A copy whose messages carry ``fn(envelope)`` instead (a node's critical-data store
        packs them, and unpacks them on restore)."""
        def item(i: _Item) -> _Item:
            return dataclasses.replace(i, env=fn(i.env))

        copy = dataclasses.replace(
            self, counter=self.counter.model_copy(deep=True),
            _arrivals=[item(i) for i in self._arrivals],
            _queues=[deque(item(i) for i in q) for q in self._queues],
            _bytes=list(self._bytes), _runs=dict(self._runs))
        if self._inflight is not None:
            copy._inflight = (item(self._inflight[0]), *self._inflight[1:])
        return copy

    def held(self) -> list[Any]:
        """Every message offered and not yet dumped (the envelopes), in delivery order: what
        is aboard, to inspect (a node's critical-data store copies it by ``with_envelopes``)."""
        items = [*self._arrivals, *(i for q in self._queues for i in q)]
        if self._inflight is not None:
            items.append(self._inflight[0])
        return [i.env for i in sorted(items, key=lambda i: i.order)]
