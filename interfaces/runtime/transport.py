"""The transport interface the Bus runs on, and the in-process transport.

A transport moves samples between Bus endpoints: a key, a message type name and the message,
as JSON bytes and/or, inside one process, as the validated object itself (:class:`Sample`).  It
delivers to an endpoint only samples published by *other* endpoints: each Bus delivers its own
messages to its own subscribers itself, identically on every transport.

JSON is made only where bytes are needed: on the wire (Zenoh) and for raw subscribers (the
recorder, the live view), once per message however many of them there are.  In one process a
Bus subscriber of the message's own type receives the publisher's (immutable) object.

The in-process network is the lean runtime of one-process runs: each (publisher, key) pair's
receivers are resolved once and cached, and a message another Bus of this process made
(``send``) goes to each receiving Bus's ``made_here`` handler, which skips the admission checks
that message cannot fail.  Raw bytes (``publish``: tools, tests, a hostile publisher) take the
full path of validation and admission, as everything arriving over Zenoh does.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from interfaces.contracts.bundle import BUNDLE_TYPE, raw_rows
from interfaces.contracts.topics import matches
from interfaces.runtime.encoding import encode

if TYPE_CHECKING:
    from interfaces.contracts.messages import Message


class Sample:
    """One message on its way between endpoints: ``key``, ``type_name``, and the message as
    ``message`` (the object, in one process; None when it came as bytes) and/or ``payload``
    (its JSON bytes, encoded from the object on first use and kept).  A bundle's sample
    keeps its rows, unpacked once for every Bus of the process (``rows``)."""

    __slots__ = ("key", "type_name", "message", "_payload", "rows")

    def __init__(self, key: str, type_name: str, payload: bytes | None = None,
                 message: Message | None = None) -> None:
        if payload is None and message is None:
            raise ValueError("a sample needs a payload or a message")
        self.key, self.type_name, self.message, self._payload = key, type_name, message, payload
        self.rows: tuple[Sample, ...] | Exception | None = None
        """A bundle's rows once unpacked, or why it has none."""

    @property
    def payload(self) -> bytes:
        """The message's JSON bytes (encoded once)."""
        if self._payload is None:
            assert self.message is not None
            self._payload = encode(self.message)
        return self._payload


SampleHandler = Callable[[Sample], None]
"""Receives a Sample (the Bus); may run on a transport thread."""
MadeHereHandler = Callable[[str, "Message"], None]
"""Receives (key, message) for a message a Bus of this process published (in-process only)."""
RawHandler = Callable[[str, str, bytes], None]
"""Receives (key, message type name, JSON payload); may run on a transport thread."""
Responder = Callable[[str], bytes | None]
"""Answers a query on a concrete key with a payload, or None for no reply."""
LivenessHandler = Callable[[str, bool], None]
"""Receives (node, alive) when a node's liveliness token appears or disappears."""


_Route = tuple[str, Callable[..., None], bool, "MadeHereHandler | None"]
"""A receiver of a key: (key expression, handler, raw, made_here), as subscribed."""


class Transport(Protocol):
    synchronous: bool
    """Whether ``send`` delivers to every receiver before it returns (the in-process network)."""

    def send(self, sample: Sample) -> None:
        """Publish a sample a Bus made (the Bus's path: bytes only if this transport needs
        them)."""

    def send_bundle(self, key: str, rows: list[Sample]) -> None:
        """Publish samples Buses of this process made as one bundle on ``key``
        (``interfaces.contracts.bundle``)."""

    def publish(self, key: str, type_name: str, payload: bytes) -> None:
        """Publish raw bytes (tools, tests: a hostile or foreign publisher)."""

    def subscribe(self, key_expr: str, handler: RawHandler) -> None:
        """Raw samples as (key, type name, JSON bytes)."""

    def subscribe_samples(self, key_expr: str, handler: SampleHandler,
                          made_here: MadeHereHandler | None = None) -> None:
        """Samples as they come: the object where the transport has it (the Bus's path).
        ``made_here``, where the transport can tell, receives instead the messages that another
        Bus of this process published (``send``)."""

    def serve(self, key_expr: str, responder: Responder) -> None: ...

    def query(self, selector: str, timeout_s: float = 2.0) -> list[tuple[str, bytes]]: ...

    def notify(self, selector: str) -> None:
        """A query whose replies nobody waits for: a notice to the queryables it reaches."""

    def declare_alive(self, node: str, token_key: str) -> None: ...

    def watch_alive(self, key_expr: str, handler: LivenessHandler) -> None: ...

    def close(self) -> None: ...


@dataclass
class InprocNetwork:
    """The shared medium of in-process transports: synchronous delivery in subscription order.
    The receivers of each (publisher, key) pair are resolved once and cached until a
    subscription or an endpoint changes."""

    _endpoints: list[InprocTransport] = field(default_factory=list)
    _lock: threading.RLock = field(default_factory=threading.RLock)
    _routes: dict[tuple[int, str], list[_Route]] = field(default_factory=dict)
    _matched: dict[tuple[str, str], bool] = field(default_factory=dict)
    """Whether a key expression matches a key, once per pair (the same expression is
    subscribed by every node of a constellation)."""

    def endpoint(self) -> InprocTransport:
        t = InprocTransport(self)
        with self._lock:
            self._endpoints.append(t)
            self._routes.clear()
        return t

    def invalidate(self) -> None:
        """Forget the cached routes (a subscription was added or an endpoint closed)."""
        with self._lock:
            self._routes.clear()

    def _targets(self, origin: InprocTransport, key: str) -> list[_Route]:
        targets = self._routes.get((id(origin), key))
        if targets is None:
            with self._lock:
                targets = [sub for ep in self._endpoints if ep is not origin and not ep.closed
                           for sub in ep.subs if self._matches(sub[0], key)]
                self._routes[(id(origin), key)] = targets
        return targets

    def _matches(self, key_expr: str, key: str) -> bool:
        hit = self._matched.get((key_expr, key))
        if hit is None:
            hit = self._matched[(key_expr, key)] = matches(key_expr, key)
        return hit

    def _deliver(self, origin: InprocTransport, sample: Sample, made_here: bool) -> None:
        key = sample.key
        for expr, handler, raw, made in self._targets(origin, key):
            if raw and sample.type_name == BUNDLE_TYPE:  # raw bytes of a bundle: its rows
                for row in raw_rows(key, sample.type_name, sample.payload):
                    if self._matches(expr, row[0]):
                        handler(*row)
            elif raw:
                handler(key, sample.type_name, sample.payload)
            elif made is not None and made_here:
                made(key, sample.message)
            else:
                handler(sample)

    def _query(self, selector: str) -> list[tuple[str, bytes]]:
        with self._lock:
            servers = [(e, r) for ep in self._endpoints if not ep.closed for e, r in ep.servers]
        out = []
        for _expr, responder in servers:
            if matches(_expr, selector):
                reply = responder(selector)
                if reply is not None:
                    out.append((selector, reply))
        return out

    def _liveness(self, node: str, alive: bool) -> None:
        with self._lock:
            watchers = [h for ep in self._endpoints if not ep.closed for h in ep.watchers]
        for h in watchers:
            h(node, alive)


@dataclass(eq=False)
class InprocTransport:
    """In-process transport: one process, no network; same API and semantics as Zenoh's."""

    network: InprocNetwork
    subs: list[tuple[str, Callable[..., None], bool, MadeHereHandler | None]] = field(
        default_factory=list)
    """(key expression, handler, raw, made_here): raw handlers get bytes, the others the
    Sample, or (key, message) through ``made_here`` for what a Bus of this process made."""
    servers: list[tuple[str, Responder]] = field(default_factory=list)
    watchers: list[LivenessHandler] = field(default_factory=list)
    alive: list[str] = field(default_factory=list)
    closed: bool = False
    synchronous: bool = True

    def send(self, sample: Sample) -> None:
        self.network._deliver(self, sample, made_here=sample.message is not None)

    def send_bundle(self, key: str, rows: list[Sample]) -> None:
        """In one process nothing travels: the rows go one after the other, as the receivers
        of a bundle take them."""
        for row in rows:
            self.send(row)

    def publish(self, key: str, type_name: str, payload: bytes) -> None:
        self.network._deliver(self, Sample(key, type_name, payload=payload), made_here=False)

    def subscribe(self, key_expr: str, handler: RawHandler) -> None:
        self.subs.append((key_expr, handler, True, None))
        self.network.invalidate()

    def subscribe_samples(self, key_expr: str, handler: SampleHandler,
                          made_here: MadeHereHandler | None = None) -> None:
        self.subs.append((key_expr, handler, False, made_here))
        self.network.invalidate()

    def serve(self, key_expr: str, responder: Responder) -> None:
        self.servers.append((key_expr, responder))

    def query(self, selector: str, timeout_s: float = 2.0) -> list[tuple[str, bytes]]:
        return self.network._query(selector)

    def notify(self, selector: str) -> None:
        self.network._query(selector)

    def declare_alive(self, node: str, token_key: str) -> None:
        self.alive.append(node)
        self.network._liveness(node, True)

    def watch_alive(self, key_expr: str, handler: LivenessHandler) -> None:
        self.watchers.append(handler)

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self.network.invalidate()
            for node in self.alive:
                self.network._liveness(node, False)
