"""Zenoh transport of the Bus (eclipse-zenoh 1.x).

A run's network (``deploy/run_constellation.py``): the run's router on the endpoint
(``tcp/127.0.0.1:7447`` by default) and every process a client of it with its own account, from
a Zenoh JSON5 config file (``config_file``: ``<out>/access/<account>.json5``, see
``deploy/access.py``).  Without a config file the settings make an open network of *peers* on
loopback (multicast scouting off; one listens on the endpoint, the others connect to it): tests
and benchmarks of the bus alone.

Messages are JSON with encoding ``application/json;<MessageType>``; publications use the BLOCK
congestion control so that nothing is dropped under pressure (the channel model, not the
middleware, decides what is lost).  Zenoh sessions must be closed explicitly: an open session
keeps the interpreter from exiting.

The nodes one process hosts (issue 42; docs/architecture.md, "Hosting") each publish on their
own session, with their own account, but receive through one :class:`SharedReceiver`: a key
expression several of them subscribe to (the tick, the truth, every observer's images) is
declared once, and what arrives is handed to each of them but its publisher, one sample whose
message the first Bus to take it decodes for all.
"""

from __future__ import annotations

import json
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import zenoh

from interfaces.contracts import topics
from interfaces.contracts.bundle import BUNDLE_TYPE, bundle_space, encode_bundle, raw_rows
from interfaces.runtime.transport import (
    LivenessHandler,
    MadeHereHandler,
    RawHandler,
    Responder,
    Sample,
    SampleHandler,
)

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"


@dataclass(frozen=True)
class ZenohSettings:
    """Where a process joins the Zenoh network."""

    connect: tuple[str, ...] = (DEFAULT_ENDPOINT,)
    listen: tuple[str, ...] = ("tcp/127.0.0.1:0",)
    mode: Literal["peer", "client", "router"] = "peer"
    config_file: str | None = None

    def config(self) -> zenoh.Config:
        if self.config_file:
            return zenoh.Config.from_file(str(Path(self.config_file)))
        c = zenoh.Config()
        c.insert_json5("mode", json.dumps(self.mode))
        c.insert_json5("scouting/multicast/enabled", "false")
        c.insert_json5("connect/endpoints", json.dumps(list(self.connect)))
        if self.mode != "client":
            c.insert_json5("listen/endpoints", json.dumps(list(self.listen)))
        return c

    @staticmethod
    def hub(endpoint: str = DEFAULT_ENDPOINT) -> ZenohSettings:
        """Settings of the process that listens on the well-known endpoint."""
        return ZenohSettings(connect=(), listen=(endpoint,))


def type_of_encoding(encoding: zenoh.Encoding) -> str:
    """Message type name carried in the encoding schema (``application/json;<Type>``)."""
    s = str(encoding)
    return s.split(";", 1)[1] if ";" in s else ""


@dataclass(eq=False)
class ZenohTransport:
    settings: ZenohSettings = field(default_factory=ZenohSettings)
    _session: Any = None
    _publishers: dict[tuple[str, str], Any] = field(default_factory=dict)
    _entities: list[Any] = field(default_factory=list)
    _lock: threading.Lock = field(default_factory=threading.Lock)
    _closed: bool = False
    synchronous: bool = False
    """Delivery happens on Zenoh's threads, after ``send`` returns."""
    shared: SharedReceiver | None = None
    """The receiver this session's node shares with the other nodes of its process (None: it
    subscribes on its own session)."""
    node: str = ""
    """The node whose session this is (needed with ``shared``: it is not handed its own
    messages)."""

    def __post_init__(self) -> None:
        self._session = zenoh.open(self.settings.config())

    @property
    def session(self) -> Any:
        return self._session

    def send(self, sample: Sample) -> None:
        self.publish(sample.key, sample.type_name, sample.payload)

    def send_bundle(self, key: str, rows: list[Sample]) -> None:
        """One message on ``key`` for all ``rows`` (``interfaces.contracts.bundle``)."""
        self.publish(key, BUNDLE_TYPE, encode_bundle((r.key, r.type_name, r.payload)
                                                     for r in rows))

    def publish(self, key: str, type_name: str, payload: bytes) -> None:
        pub = self._publishers.get((key, type_name))
        if pub is None:
            with self._lock:
                pub = self._session.declare_publisher(
                    key,
                    encoding=zenoh.Encoding.APPLICATION_JSON.with_schema(type_name),
                    congestion_control=zenoh.CongestionControl.BLOCK,
                    allowed_destination=(zenoh.Locality.REMOTE if self.shared is None
                                         else zenoh.Locality.ANY),  # its process's receiver
                )
                self._publishers[(key, type_name)] = pub
        pub.put(payload)

    def subscribe(self, key_expr: str, handler: RawHandler) -> None:
        """Raw samples on ``key_expr``; of a bundle, its rows on keys ``key_expr`` matches, as
        if each had come alone (``interfaces.contracts.bundle``): also from bundles on keys
        outside ``key_expr``."""
        def on_sample(sample: zenoh.Sample) -> None:
            key, type_name = str(sample.key_expr), type_of_encoding(sample.encoding)
            if type_name != BUNDLE_TYPE:
                handler(key, type_name, sample.payload.to_bytes())
                return
            for row in raw_rows(key, type_name, sample.payload.to_bytes()):
                if topics.matches(key_expr, row[0]):
                    handler(*row)

        self.declare_subscriber(key_expr, on_sample, zenoh.Locality.REMOTE)
        bundles = _bundles_for(key_expr)
        if bundles is not None:
            self.declare_subscriber(bundles, on_sample, zenoh.Locality.REMOTE)

    def declare_subscriber(self, key_expr: str, callback: Callable[[zenoh.Sample], None],
                           origin: zenoh.Locality) -> None:
        """A Zenoh subscriber on this session, undeclared when it closes."""
        self._entities.append(
            self._session.declare_subscriber(key_expr, callback, allowed_origin=origin))

    def subscribe_samples(self, key_expr: str, handler: SampleHandler,
                          made_here: MadeHereHandler | None = None) -> None:
        """Every sample comes as bytes, to be validated and admitted by the Bus (``made_here``
        is never called); through the process's ``shared`` receiver, if it has one."""
        if self.shared is not None:
            self.shared.subscribe(self, key_expr, handler)
            return
        self.declare_subscriber(key_expr, lambda s: handler(_sample(s)), zenoh.Locality.REMOTE)

    def serve(self, key_expr: str, responder: Responder) -> None:
        def on_query(query: zenoh.Query) -> None:
            k = str(query.key_expr) if query.key_expr is not None else str(query.selector)
            reply = responder(k)
            if reply is not None:
                query.reply(k, reply, encoding=zenoh.Encoding.APPLICATION_JSON)

        self._entities.append(self._session.declare_queryable(key_expr, on_query))

    def query(self, selector: str, timeout_s: float = 2.0) -> list[tuple[str, bytes]]:
        out = []
        for reply in self._session.get(selector, timeout=timeout_s):
            if reply.ok is not None:
                out.append((str(reply.ok.key_expr), reply.ok.payload.to_bytes()))
        return out

    def notify(self, selector: str) -> None:
        """Send a query whose replies nobody waits for (a notice to the queryables it
        reaches); returns at once.  The replies go to a channel of one that nobody reads: a
        Python callback would start a thread of its own for every notice."""
        self._session.get(selector, zenoh.handlers.RingChannel(1))

    def declare_alive(self, node: str, token_key: str) -> None:
        self._entities.append(self._session.liveliness().declare_token(token_key))

    def watch_alive(self, key_expr: str, handler: LivenessHandler) -> None:
        def on_sample(sample: zenoh.Sample) -> None:
            node = _node_from_token(str(sample.key_expr))
            if node is not None:
                handler(node, sample.kind == zenoh.SampleKind.PUT)

        self._entities.append(
            self._session.liveliness().declare_subscriber(key_expr, on_sample, history=True)
        )

    def close(self) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
        for e in reversed(self._entities):
            try:
                e.undeclare()
            except Exception:  # noqa: BLE001 - best effort on shutdown
                pass
        for p in self._publishers.values():
            try:
                p.undeclare()
            except Exception:  # noqa: BLE001
                pass
        self._session.close()


@dataclass(eq=False)
class SharedReceiver:
    """What the nodes one process hosts receive, taken from Zenoh once (module docstring).

    Each key expression is declared once, on the session of the first node that subscribes to
    it, with samples of any origin: the process's own nodes publish on their own sessions, so a
    message one of them sends reaches the others through it (from that very session without
    the router).  A sample is handed to every node subscribed to the expression except the
    owner of its key, the node that published it (a Bus delivers its own messages itself), as
    one :class:`Sample`: the first Bus to validate it keeps the message on it and the others
    take that (``Bus._admitted``), each admitting it by its own rules."""

    _receivers: dict[str, tuple[tuple[str, SampleHandler], ...]] = field(default_factory=dict)
    """By key expression: (node, handler) of each node subscribed to it."""
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def subscribe(self, transport: ZenohTransport, key_expr: str,
                  handler: SampleHandler) -> None:
        """``handler`` of ``transport``'s node receives what arrives on ``key_expr``."""
        if not transport.node:
            raise ValueError("a session sharing its process's receiver must name its node")
        with self._lock:
            known = self._receivers.get(key_expr)
            self._receivers[key_expr] = (*(known or ()), (transport.node, handler))
            if known is None:
                transport.declare_subscriber(
                    key_expr, lambda s, e=key_expr: self._on_sample(e, s), zenoh.Locality.ANY)

    def _on_sample(self, key_expr: str, zsample: zenoh.Sample) -> None:
        sample = _sample(zsample)
        key = sample.key
        publisher = topics.node_of_key(key)
        for node, handler in self._receivers[key_expr]:
            if node != publisher:
                try:
                    handler(sample)
                except Exception:  # noqa: BLE001 - one node's failure is not the others'
                    logging.getLogger(f"insp.bus.{node}").exception(
                        "%s: taking in a sample on %s failed", node, key)


def _sample(zsample: zenoh.Sample) -> Sample:
    """A Zenoh sample as the Bus takes it: key, type name, JSON bytes."""
    return Sample(str(zsample.key_expr), type_of_encoding(zsample.encoding),
                  payload=zsample.payload.to_bytes())


def _bundles_for(key_expr: str) -> str | None:
    """The bundles whose rows a raw subscription on ``key_expr`` may need and does not receive
    by its own expression (None: it receives them, or none can match)."""
    parts = key_expr.split("/")
    if parts[0] not in (topics.ROOT, "*", "**"):
        return None  # nothing under insp/ matches it
    named = parts[0] == topics.ROOT and len(parts) > 1 and parts[1] not in ("*", "**")
    space = bundle_space(parts[1] if named else "*")
    return None if topics.matches(key_expr, space.replace("*", "x")) else space


def _node_from_token(token_key: str) -> str | None:
    """Liveliness tokens are ``<node prefix>/alive`` (the recorder's ``topics.recorder_token``):
    recover the node name (``topics.RECORDER`` for the recorder)."""
    parts = token_key.split("/")
    if parts[-1] != "alive":
        return None
    if len(parts) == 5 and parts[2] == "sc" and parts[3].isdigit():
        return f"sc{int(parts[3])}"
    if len(parts) == 4 and parts[2] in ("sim", "ground"):
        return parts[2]
    if len(parts) == 5 and parts[2:4] == ["ground", topics.RECORDER]:
        return topics.RECORDER
    return None
