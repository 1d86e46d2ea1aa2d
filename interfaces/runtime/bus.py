"""The software bus: typed publish/subscribe over a transport (Zenoh or in-process).

What the Bus guarantees, identically on every transport:

* **Own key space.** A node publishes only under its own prefix (``topics.node_prefix``).
* **Typed topics.** A key of the topic catalogue (``interfaces.contracts.catalogue``) is published
  and subscribed with its catalogue type only; anything else is a programming error (TypeError).
* **Sequence numbers.** Each key has its own sequence count starting at 1, set on publish.
* **Validation where bytes come in.** A received payload that is not valid JSON of the subscribed
  model (wrong fields, NaN, oversize) is dropped, counted in ``invalid_dropped`` and logged;
  nothing else happens, the node goes on.  In one process (in-process transport) a subscriber
  of the message's own type receives the publisher's validated, immutable object, with no JSON
  in between; JSON is made only for the transports and raw subscribers that need bytes.
* **Admission.** A valid message is then held to the plausibility rules of
  ``interfaces.runtime.admission`` (its sender owns the key, a sane sequence number and date, a
  bounded queue); a refused one is counted in ``refused`` and logged, and never reaches the barrier.
  One already seen (same key and number) is a duplicate: dropped, counted, not logged.
* **Deterministic delivery.** Deferred subscriptions (the default) are delivered by
  ``dispatch(t_now)`` on the caller's thread, sorted by (send time, key, sequence).  Messages of
  other flight/ground nodes become eligible one tick after they were sent (at the earliest) and
  after the channel delay; sim messages (sensors, truth) as soon as the tick they belong to runs.
  Immediate subscriptions run on the transport thread (the executive's tick, the recorder).
* **Channel.** Messages between two different spacecraft/ground nodes pass the receiver's
  ``ChannelModel`` (range at send time, loss, cuts, delay) at dispatch.  With ground passes
  the space-ground ones wait there (stored onboard, or held on the ground) and come back
  from it when they reach the receiver (``links.space_ground``).
* **Bundles.** With a process bundle (``bundle``), what never passes the link stage (the
  catalogue's ``bundled`` topics) is handed to it instead of the transport and travels, over
  Zenoh, as one message per process and tick (``interfaces.contracts.bundle``,
  ``interfaces.runtime.bundle_out``).  A bundle received is taken row by row as if each had
  come alone, each row only from the process that hosts its node (else refused, ``stranger``).
* **Barrier.** ``wait_for(expect)`` blocks until the messages announced in a Tick have arrived.
* **Recovery.** Each node keeps what it sent in its last ticks and sends it again to a node that
  asks (``interfaces.runtime.recent``): ``recover`` fetches what a tick announced and never came.
  With a recorder, it keeps too what the recorder has not yet archived for good, so that a
  recorder restarted takes back what it lost (bounded; what is forgotten is counted lost).

The Bus's parts of their own: the subscription table (``interfaces.runtime.subscriptions``), the
inbox of deferred messages with the delivery order and the barrier (``interfaces.runtime.inbox``),
admission (``interfaces.runtime.admission``), the link stage (``interfaces.runtime.link_stage``)
and the schema service (``interfaces.runtime.schemas``).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

from pydantic import ValidationError

from interfaces.contracts import catalogue, topics
from interfaces.contracts.bundle import (
    BundleError,
    bundle_space,
    decode_bundle,
    row_admissible,
    row_spaces,
)
from interfaces.contracts.messages import Message, TruthState, stamp
from interfaces.runtime.admission import MAX_SEQ_JUMP, Admission
from interfaces.runtime.bundle_out import BundleOut
from interfaces.runtime.inbox import Envelope, Inbox
from interfaces.runtime.link_stage import LinkStage
from interfaces.runtime.recent import RECENT_TICKS, RecentSent, archived_queryable
from interfaces.runtime.schemas import serve_schemas
from interfaces.runtime.subscriptions import Route, Sub, SubscriptionTable
from interfaces.runtime.transport import LivenessHandler, RawHandler, Sample, Transport

M = TypeVar("M", bound=Message)
MAX_PAYLOAD_BYTES = 1 << 20


@dataclass
class BusStats:
    published: int = 0
    received: int = 0
    invalid_dropped: int = 0
    handler_errors: int = 0
    channel_dropped: int = 0
    refused: int = 0


@dataclass(eq=False)
class Bus:
    """Node ``node``'s side of the bus of ``mission`` (module docstring); its subscriptions are
    in ``table`` (``interfaces.runtime.subscriptions``), the messages waiting for delivery and
    the barrier in ``inbox`` (``interfaces.runtime.inbox``)."""

    node: str
    mission: str
    transport: Transport
    channel: LinkStage | None = None
    log: logging.Logger = field(default=None)  # type: ignore[assignment]
    stats: BusStats = field(default_factory=BusStats)
    admission: Admission = field(default_factory=Admission)
    recent_ticks: int = RECENT_TICKS
    """Ticks of sent messages kept for resend requests (``interfaces.runtime.recent``)."""
    bundle: BundleOut | None = None
    """The process's outgoing bundle, shared by its Buses (None: every message goes alone)."""
    _seq: dict[str, int] = field(default_factory=dict)
    _published_since: dict[str, int] = field(default_factory=dict)
    _raw: dict[str, list[RawHandler]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.prefix = topics.node_prefix(self.mission, self.node)
        self.table = SubscriptionTable(self.prefix)
        self.inbox = Inbox(self.node)
        self.recent = RecentSent(self.recent_ticks)
        self._arriving: set[tuple[str, int]] = set()
        """(key, number) of the messages being taken in on some thread right now."""
        if self.log is None:
            self.log = logging.getLogger(f"insp.bus.{self.node}")
        feed = self.channel.truth_feed() if self.channel is not None else None
        if feed is not None:
            self.subscribe(catalogue.TRUTH.key(self.mission), TruthState, feed, immediate=True)
        self.transport.subscribe_samples(bundle_space(self.mission), self._on_bundle)

    # --- publishing ------------------------------------------------------------------------

    def publish(self, key: str, msg: Message, announce: bool = True) -> None:
        """Publish ``msg`` on ``key`` (which must be in this node's key space).

        Sets ``sender``, ``seq`` and ``t_wall``.  Treat a published message as immutable.
        ``announce=False`` leaves the key out of ``published_since_last`` (lockstep control
        messages that nobody must wait for)."""
        route = self.table.routes.get(key)
        if route is None:
            route = self._route(key)
        expected, local, bundled = route
        if expected is not None and type(msg) is not expected:
            raise TypeError(f"{key} carries {expected.__name__}, not {type(msg).__name__}")
        seq = self._seq.get(key, 0) + 1
        self._seq[key] = seq
        if announce:
            self._published_since[key] = seq
        stamp(msg, self.node, seq, time.time())
        self.stats.published += 1
        if local:
            inbox = self.inbox
            with inbox.lock:
                for sub in local:
                    inbox.pending.append(Envelope(msg, key, self.node, True, [sub]))
        sample = Sample(key, type(msg).__name__, message=msg)
        self.recent.add(sample)
        if bundled and self.bundle is not None:
            self.bundle.add(sample)
        else:
            self.transport.send(sample)

    def flush_bundle(self) -> None:
        """Send the process's bundle (the end of its tick; nothing without one)."""
        if self.bundle is not None:
            self.bundle.flush()

    def _route(self, key: str) -> Route:
        """What publishing on ``key`` needs, checked and resolved once: the key is in this
        node's space, its catalogue type, this node's own subscribers of it."""
        if not key.startswith(self.prefix + "/"):
            raise ValueError(f"node {self.node} may not publish on {key!r} "
                             f"(own space: {self.prefix})")
        return self.table.route(key)

    def published_since_last(self) -> dict[str, int]:
        """Keys published since the previous call, with their last sequence number."""
        out, self._published_since = self._published_since, {}
        forgotten = self.recent.forgotten
        self.recent.next_tick()
        if self.recent.forgotten != forgotten:
            self.log.warning("%s forgot %d message(s) the recorder has not archived (%d so "
                             "far): they will be counted lost", self.node,
                             self.recent.forgotten - forgotten, self.recent.forgotten)
        return out

    # --- subscribing -----------------------------------------------------------------------

    def subscribe(
        self,
        key_expr: str,
        msg_type: type[M],
        handler: Callable[[M], None],
        immediate: bool = False,
    ) -> None:
        """Deliver messages of ``msg_type`` on ``key_expr`` to ``handler``: at ``dispatch`` time
        (default) or at once on the transport thread (``immediate``)."""
        self.table.check_type(key_expr, msg_type)
        if key_expr not in self.table.groups:
            self.transport.subscribe_samples(
                key_expr, lambda smp, e=key_expr: self._on_sample(e, smp),
                made_here=lambda key, msg, e=key_expr: self._on_made_here(e, key, msg))
        self.table.add(Sub(key_expr, msg_type, handler, immediate))  # type: ignore[arg-type]

    def subscriptions(self) -> dict[str, list[type[Message]]]:
        """The typed subscriptions of this node: key expression -> subscribed message types."""
        return self.table.types()

    def subscribe_raw(self, key_expr: str, handler: RawHandler) -> None:
        """Raw samples (key, type name, payload) at once, unvalidated (recorder, tools)."""
        self._raw.setdefault(key_expr, []).append(handler)
        self.transport.subscribe(key_expr, handler)

    def _on_sample(self, key_expr: str, sample: Sample) -> None:
        """Transport callback (any thread): validate bytes (an object of the subscribed type is
        taken as it is), admit, count, call or queue.  A message is queued and its sequence
        number recorded in one step, so the barrier never wakes for a message not yet queued."""
        self.stats.received += 1
        key = sample.key
        if sample.message is None and len(sample.payload) > MAX_PAYLOAD_BYTES:
            self.drop_invalid(key, f"payload of {len(sample.payload)} bytes exceeds "
                               f"{MAX_PAYLOAD_BYTES}")
            return
        decoded: dict[type[Message], Message] = {}
        group = self.table.groups.get(key_expr, [])
        for sub in group:
            if sub.msg_type not in decoded:
                msg = self._admitted(key, sub.msg_type, sample)
                if msg is None:
                    return
                decoded[sub.msg_type] = msg
        if not decoded:
            return
        first = next(iter(decoded.values()))
        if not self._claim(key, first):
            return
        try:  # the immediate handlers first: the barrier must not wake before they ran
            for sub in group:
                if sub.immediate:
                    self._call(sub, decoded[sub.msg_type], key)
        finally:
            self._queue(key, group, decoded, (key, first.seq))

    def _on_bundle(self, sample: Sample) -> None:
        """A bundle (``interfaces.contracts.bundle``, any thread): every row but this node's
        own taken as if it had come alone, on each subscription its key matches; a row outside
        the key spaces of the nodes its process hosts is refused (``stranger``), a malformed
        bundle dropped whole.  Its rows, or why it has none, are unpacked once for every Bus
        of the process."""
        if sample.rows is None:
            try:
                sample.rows = tuple(Sample(k, t, payload=p)
                                    for k, t, p in decode_bundle(sample.payload))
            except BundleError as e:
                sample.rows = e
        if isinstance(sample.rows, BundleError):
            self.drop_invalid(sample.key, f"not a valid bundle: {sample.rows}")
            return
        spaces, own = row_spaces(sample.key), self.prefix + "/"
        for row in sample.rows:
            exprs = self.table.matching(row.key)
            if not exprs or row.key.startswith(own):
                continue
            if not row_admissible(spaces, row.key):
                self.refuse(row.key, "stranger", f"in the bundle of {sample.key}, outside the "
                            "key spaces of the nodes its process hosts")
                continue
            for expr in exprs:
                self._on_sample(expr, row)

    def _claim(self, key: str, msg: Message) -> bool:
        """Whether ``msg`` is new to this node (not admitted yet, nor arriving on another
        thread right now: a resent copy and the late original); it is then arriving until
        ``_queue``."""
        with self.inbox.lock:
            if (key, msg.seq) in self._arriving:
                self.admission.duplicates += 1
                return False
            if self.admission.duplicate(key, msg):
                return False
            self._arriving.add((key, msg.seq))
            return True

    def _queue(self, key: str, group: list[Sub], decoded: dict[type[Message], Message],
               arriving: tuple[str, int]) -> None:
        """Queue a claimed message for its deferred subscribers (one envelope per message,
        whatever their number: the channel decides once, so every app of the node sees the
        same messages), and record its number for the barrier, in one step."""
        src = self.admission.owner(key)
        inbox = self.inbox
        with inbox.lock:
            self._arriving.discard(arriving)
            deferred: dict[int, tuple[Message, list[Sub]]] = {}
            for sub in group:
                if not sub.immediate:
                    msg = decoded[sub.msg_type]
                    deferred.setdefault(id(msg), (msg, []))[1].append(sub)
            for msg, subs in deferred.values():
                inbox.pending.append(Envelope(msg, key, src, False, subs))
            for msg in decoded.values():
                self.admission.admit(key, msg)
            inbox.wake()

    def _on_made_here(self, key_expr: str, key: str, msg: Message) -> None:
        """In-process callback: a message another Bus of this process published.  It was
        made valid and its publisher's Bus set its sender and sequence number, so the admission
        checks cannot fail it and are skipped; it is delivered, queued and recorded for the
        barrier exactly as an admitted sample (``_on_sample``)."""
        group = self.table.split[key_expr]
        if type(msg) is not group.kind:  # subscribed as other types: validate from JSON
            self._on_sample(key_expr, Sample(key, type(msg).__name__, message=msg))
            return
        self.stats.received += 1
        for sub in group.immediate:
            self._call(sub, msg, key)
        inbox = self.inbox
        with inbox.lock:
            highest = self.admission.highest_seq
            if group.deferred:
                inbox.pending.append(Envelope(msg, key, self.admission.owner(key), False,
                                              group.deferred))
            if msg.seq > highest.get(key, 0):  # Admission.admit, inlined
                highest[key] = msg.seq
            inbox.wake()

    def _admitted(self, key: str, msg_type: type[Message], sample: Sample) -> Message | None:
        """The sample as a ``msg_type`` that passes admission, or None (dropped, counted)."""
        msg = sample.message
        if type(msg) is not msg_type:
            try:
                msg = msg_type.model_validate_json(sample.payload)
            except ValidationError as e:
                self.drop_invalid(key, f"not a valid {msg_type.__name__}: {_first_error(e)}")
                return None
            if sample.message is None:  # the other nodes of this process handed the same
                sample.message = msg  # sample take it as it is (``SharedReceiver``)
        refusal = self.admission.check(key, msg, len(self.inbox.pending))
        if refusal is not None:
            self.refuse(key, *refusal)
            return None
        return msg

    def refuse(self, key: str, kind: str, why: str) -> None:
        """Count and log (rate-limited) a message refused on ``key`` (see ``Admission``)."""
        self.admission.refused[kind] += 1
        self.stats.refused += 1
        n = self.stats.refused
        if n <= 5 or n % 1000 == 0:
            self.log.warning("%s refused message #%d on %s (%s): %s", self.node, n, key, kind,
                             why)

    def drop_invalid(self, key: str, why: str) -> None:
        """Count and log (rate-limited) an invalid message on ``key``."""
        self.stats.invalid_dropped += 1
        n = self.stats.invalid_dropped
        if n <= 5 or n % 100 == 0:
            self.log.warning("%s dropped invalid message #%d on %s: %s", self.node, n, key, why)

    def _call(self, sub: Sub, msg: Message, key: str) -> None:
        try:
            sub.handler(msg)
        except Exception:  # noqa: BLE001 - a handler's failure must not stop the node
            self.stats.handler_errors += 1
            self.log.exception("%s: handler for %s failed", self.node, key)

    # --- delivery --------------------------------------------------------------------------

    def dispatch(self, t_now: float, include_now: bool = False) -> int:
        """Deliver the deferred messages that are due at ``t_now`` (s), in deterministic order.

        Messages from other spacecraft/ground nodes are due once sent strictly before ``t_now``
        (or at ``t_now`` with ``include_now``) and their channel delay has elapsed; local and sim
        messages once their time is ``<= t_now`` (``Inbox.take_due``).  Returns the number of
        messages delivered."""
        delay = self.channel.delay_s if self.channel is not None else 0.0
        self.admission.advance(t_now)
        delivered = 0
        channel = self.channel
        for env in self.inbox.take_due(t_now, include_now, delay):
            if not env.local and channel is not None and self.inbox.crosses_link(env.src):
                fate = channel.transmit(env.src or "", env.key, env.msg, env)
                if fate == "drop":
                    self.stats.channel_dropped += 1
                if fate != "deliver":
                    continue  # dropped, or waits on a link: comes back from ``released``
            delivered += self._deliver(env)
        if channel is not None:
            for env in channel.released(t_now):
                delivered += self._deliver(env)
        return delivered

    def _deliver(self, env: Envelope) -> int:
        for sub in env.subs:
            self._call(sub, env.msg, env.key)
        return 1

    def wait_for(self, expect: dict[str, int], timeout_s: float) -> list[str]:
        """Block until every key of ``expect`` that this node subscribes to (and does not own)
        has arrived up to its sequence number; return the keys still missing at the timeout.
        An announced number that admission would refuse (``MAX_SEQ_JUMP`` past the highest seen)
        is not waited for."""
        seen = self.admission.highest_seq
        wanted = {k: s for k, s in expect.items()
                  if self.table.awaits(k) and s <= seen.get(k, 0) + MAX_SEQ_JUMP}
        return self.inbox.wait(wanted, seen, timeout_s)

    def take_in(self, sample: Sample) -> int:
        """Receive ``sample`` as if it had just arrived (validated, admitted: one already held
        is a duplicate), unless it is the lockstep's tick (its subscriber judges ticks as they
        come; old ones are no news).  Returns 1 if it was taken (new, valid, admitted)."""
        if sample.key in self.admission.judged_by_subscriber:
            return 0
        expr = next((e for e in self.table.groups if topics.matches(e, sample.key)), None)
        if expr is None:
            return 0
        before = self._dropped()
        self._on_sample(expr, sample)
        return 1 if self._dropped() == before else 0

    def _dropped(self) -> tuple[int, int, int]:
        """What this node dropped so far: duplicates, invalid, refused."""
        return self.admission.duplicates, self.stats.invalid_dropped, self.stats.refused

    # --- restarts --------------------------------------------------------------------------

    def checkpoint(self) -> dict[str, Any]:
        """What this Bus learnt while running, for the node's critical-data store
        (``interfaces.runtime.checkpoint``): its sequence counts and statistics, admission's
        state (highest numbers seen, clock, counts), the messages waiting in the inbox (their
        subscribers by key expression and place) and the channel stage's (the truth it judges
        ranges on from the oldest message waiting or the clock, whichever is earlier: nothing
        sent before either is still to come), and what it sent in its last ticks (``recent``).
        The values are the Bus's own: pickle them at once."""
        index = {id(s): (e, i) for e, group in self.table.groups.items()
                 for i, s in enumerate(group)}
        with self.inbox.lock:  # the receiving threads queue and admit under it: copies
            pending = [_pack(e, index) for e in self.inbox.pending]
            admission = self.admission.checkpoint()
            stats = dataclasses.replace(self.stats)
        since = min([admission["clock_s"] or 0.0, *(m[0].t_sim for m in pending)])
        channel = (None if self.channel is None else
                   self.channel.checkpoint(since, lambda e: _pack(e, index)))
        return {"seq": dict(self._seq), "stats": stats, "admission": admission,
                "pending": pending, "channel": channel, "recent": self.recent.checkpoint()}

    def restore(self, saved: dict[str, Any]) -> None:
        """Take back a ``checkpoint`` into a Bus wired as the one that took it."""
        if (saved["channel"] is None) != (self.channel is None):
            raise ValueError("the store's channel stage does not match the node's")
        groups = self.table.groups
        self._seq, self.stats = saved["seq"], saved["stats"]
        with self.inbox.lock:
            self.admission.restore(saved["admission"])
            self.inbox.pending = [_unpack(p, groups) for p in saved["pending"]]
        if self.channel is not None:
            self.channel.restore(saved["channel"], lambda p: _unpack(p, groups))
        self.recent.restore(saved["recent"])

    # --- services --------------------------------------------------------------------------

    def number_afresh(self) -> None:
        """Number this node's messages from 1 again on every key (a restored node that could
        not run again every tick since its store: its receivers saw higher numbers, and take
        its new ones as a publisher started afresh, ``Admission.restarted``)."""
        self._seq = {}

    def send_again(self, key: str, msg: Message) -> None:
        """Send again the answer to the last tick this node ran, ``msg``, as it was (same
        number), and before it what else the node sent in that tick (``RecentSent.last_tick``;
        not the answer to the tick before, sent in it too):
        the sim not having the answer, the tick's messages may be lost too, with the network
        or with the process, killed before its transport sent them (restored from its store of
        that tick, it does not run the tick again).  A receiver that had them drops them as
        duplicates, one that missed them takes them; the recorder writes them, and the archive
        keeps each once."""
        for sample in self.recent.last_tick():
            if sample.key != key:
                self.transport.send(sample)
        self.transport.send(Sample(key, type(msg).__name__, message=msg))

    def serve_recent(self) -> None:
        """Answer ``<prefix>/bus/recent`` with what this node sent in its last ticks, and keep
        from now on also what the run's recorder has not archived, until it says it has
        (``<prefix>/bus/archived/<t_ns>``: ``interfaces.runtime.recent``)."""
        self.recent.keep_until_archived()
        self.transport.serve(topics.recent_queryable(self.mission, self.node), self.recent.reply)
        self.transport.serve(archived_queryable(self.mission, self.node), self.recent.archived)

    def serve_schemas(self) -> None:
        """Answer ``<prefix>/schema/<Type>`` queries with the message type's JSON schema
        (``interfaces.runtime.schemas``)."""
        serve_schemas(self.transport, self.mission, self.node)

    def declare_alive(self) -> None:
        """Announce this node (Zenoh liveliness token ``<prefix>/alive``)."""
        self.transport.declare_alive(self.node, topics.alive_token(self.mission, self.node))

    def watch_alive(self, handler: LivenessHandler) -> None:
        self.transport.watch_alive(f"{topics.ROOT}/{self.mission}/**/alive", handler)

    def close(self) -> None:
        self.transport.close()


Packed = tuple[Message, str, "str | None", bool, list[tuple[str, int]]]
"""An envelope as a critical-data store keeps it: its subscribers by key expression and place."""


def _pack(env: Envelope, index: dict[int, tuple[str, int]]) -> Packed:
    return env.msg, env.key, env.src, env.local, [index[id(s)] for s in env.subs]


def _unpack(packed: Packed, groups: dict[str, list[Sub]]) -> Envelope:
    msg, key, src, local, which = packed
    return Envelope(msg, key, src, local, [groups[e][i] for e, i in which])


def _first_error(e: ValidationError) -> str:
    err = e.errors()[0]
    where = ".".join(str(x) for x in err["loc"])
    return f"{where}: {err['msg']}" if where else err["msg"]
