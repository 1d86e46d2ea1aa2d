"""The transport interface the Bus runs on, and the in-process transport.

A transport moves raw samples ``(key, type_name, payload)`` between Bus endpoints.  It delivers
to an endpoint only samples published by *other* endpoints: each Bus delivers its own messages
to its own subscribers itself, identically on every transport.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from interfaces.topics import matches

RawHandler = Callable[[str, str, bytes], None]
"""Receives (key, message type name, JSON payload); may run on a transport thread."""
Responder = Callable[[str], bytes | None]
"""Answers a query on a concrete key with a payload, or None for no reply."""
LivenessHandler = Callable[[str, bool], None]
"""Receives (node, alive) when a node's liveliness token appears or disappears."""


class Transport(Protocol):
    def publish(self, key: str, type_name: str, payload: bytes) -> None: ...

    def subscribe(self, key_expr: str, handler: RawHandler) -> None: ...

    def serve(self, key_expr: str, responder: Responder) -> None: ...

    def query(self, selector: str, timeout_s: float = 2.0) -> list[tuple[str, bytes]]: ...

    def declare_alive(self, node: str, token_key: str) -> None: ...

    def watch_alive(self, key_expr: str, handler: LivenessHandler) -> None: ...

    def close(self) -> None: ...


@dataclass
class InprocNetwork:
    """The shared medium of in-process transports: synchronous delivery in subscription order.
    The handlers of each (publisher, key) pair are resolved once and cached until a subscription
    or an endpoint changes."""

    _endpoints: list[InprocTransport] = field(default_factory=list)
    _lock: threading.RLock = field(default_factory=threading.RLock)
    _routes: dict[tuple[int, str], list[RawHandler]] = field(default_factory=dict)

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

    def _deliver(self, origin: InprocTransport, key: str, type_name: str, payload: bytes) -> None:
        with self._lock:
            targets = self._routes.get((id(origin), key))
            if targets is None:
                targets = [
                    h for ep in self._endpoints if ep is not origin and not ep.closed
                    for expr, h in ep.subs if matches(expr, key)
                ]
                self._routes[(id(origin), key)] = targets
        for h in targets:
            h(key, type_name, payload)

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
    subs: list[tuple[str, RawHandler]] = field(default_factory=list)
    servers: list[tuple[str, Responder]] = field(default_factory=list)
    watchers: list[LivenessHandler] = field(default_factory=list)
    alive: list[str] = field(default_factory=list)
    closed: bool = False

    def publish(self, key: str, type_name: str, payload: bytes) -> None:
        self.network._deliver(self, key, type_name, payload)

    def subscribe(self, key_expr: str, handler: RawHandler) -> None:
        self.subs.append((key_expr, handler))
        self.network.invalidate()

    def serve(self, key_expr: str, responder: Responder) -> None:
        self.servers.append((key_expr, responder))

    def query(self, selector: str, timeout_s: float = 2.0) -> list[tuple[str, bytes]]:
        return self.network._query(selector)

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
