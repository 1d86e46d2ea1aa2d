"""A Bus's subscription table: which of the node's handlers take which key expression, as which
message type, and what follows from that for each concrete key.

* **Typed topics.** A key of the topic catalogue (``interfaces.contracts.catalogue``) is
  subscribed (and published) with its catalogue type only: ``check_type`` raises TypeError.
* **Routes.** For a key the node publishes on: its catalogue type and the node's own subscribers
  of it (``route``), resolved once per key.
* **Awaited keys.** For a key a Tick announces: whether the barrier waits for it (another node's
  key that a subscription covers, ``awaits``).

Everything resolved per key is cached until the next subscription.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field

from interfaces.contracts import catalogue, topics
from interfaces.contracts.messages import Message

_UNKNOWN = object()
"""Marks a key not yet looked up in the catalogue."""


@dataclass
class Sub:
    """One subscription: ``handler`` takes the ``msg_type`` messages on ``key_expr``, at dispatch
    time or at once on the transport thread (``immediate``)."""

    key_expr: str
    msg_type: type[Message]
    handler: Callable[[Message], None]
    immediate: bool


@dataclass
class Group:
    """The subscriptions of one key expression, split for delivery of a message of ``kind``
    (the type all of them take, or None when they take different types)."""

    kind: type[Message] | None
    immediate: list[Sub]
    deferred: list[Sub]

    @classmethod
    def of(cls, subs: list[Sub]) -> Group:
        kinds = {s.msg_type for s in subs}
        return cls(kinds.pop() if len(kinds) == 1 else None,
                   [s for s in subs if s.immediate], [s for s in subs if not s.immediate])


Route = tuple[type[Message] | None, list[Sub], bool]
"""What publishing on a key needs: its catalogue type (None: not catalogued), the node's own
subscribers of it, and whether it travels in its process's bundle (the catalogue's
``bundled``)."""
_MAX_CACHED_KEYS = 4096
"""Keys whose matching expressions are kept (beyond: looked up every time)."""


@dataclass(eq=False)
class SubscriptionTable:
    """The subscriptions of the node whose key space is ``prefix`` (``topics.node_prefix``)."""

    prefix: str
    groups: dict[str, list[Sub]] = field(default_factory=dict)
    """Subscriptions by key expression, in subscription order."""
    split: dict[str, Group] = field(default_factory=dict)
    """The same, split for delivery (``Group``)."""
    routes: dict[str, Route] = field(default_factory=dict)
    """Per key published: its route (``route``), once resolved."""
    _awaited: dict[str, bool] = field(default_factory=dict)
    _key_types: dict[str, object] = field(default_factory=dict)
    """Catalogue topic of each key published or subscribed (None: not catalogued)."""
    _matching: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """Per key received in a bundle: the key expressions subscribed that match it (looked up
    on the transport's threads, under ``_lock`` with ``add``)."""
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def add(self, sub: Sub) -> None:
        """Add ``sub``, of a type ``check_type`` accepted; forget what was resolved."""
        with self._lock:
            group = self.groups.setdefault(sub.key_expr, [])
            group.append(sub)
            self.split[sub.key_expr] = Group.of(group)
            self.routes.clear()
            self._awaited.clear()
            self._matching.clear()

    def types(self) -> dict[str, list[type[Message]]]:
        """Key expression -> subscribed message types."""
        return {e: [s.msg_type for s in g] for e, g in self.groups.items()}

    def catalogue_type(self, key: str) -> type[Message] | None:
        """The message type the catalogue gives ``key`` (None: not catalogued), cached."""
        topic = self._topic(key)
        return None if topic is None else topic.type

    def _topic(self, key: str) -> catalogue.Topic | None:
        """The catalogue's topic of ``key`` (None: not catalogued), looked up once a key."""
        topic = self._key_types.get(key, _UNKNOWN)
        if topic is _UNKNOWN:
            topic = self._key_types[key] = catalogue.topic_of(key)
        return topic  # type: ignore[return-value]

    def check_type(self, key: str, msg_type: type[Message]) -> None:
        """A catalogued key carries its catalogue type only (``interfaces.contracts.catalogue``)."""
        expected = self.catalogue_type(key)
        if expected is not None and msg_type is not expected:
            raise TypeError(f"{key} carries {expected.__name__}, not {msg_type.__name__}")

    def route(self, key: str) -> Route:
        """Resolve and cache ``key``'s route: its catalogue type, the node's own subscribers,
        whether it is bundled."""
        topic = self._topic(key)
        route = self.routes[key] = (
            None if topic is None else topic.type,
            [s for e, g in self.groups.items() if topics.matches(e, key) for s in g],
            topic is not None and topic.bundled)
        return route

    def matching(self, key: str) -> tuple[str, ...]:
        """The subscribed key expressions that match ``key`` (cached for a bounded number of
        keys)."""
        hit = self._matching.get(key)
        if hit is None:
            with self._lock:  # never a match made before a subscription kept after it
                hit = tuple(e for e in self.groups if topics.matches(e, key))
                if len(self._matching) < _MAX_CACHED_KEYS:
                    self._matching[key] = hit
        return hit

    def awaits(self, key: str) -> bool:
        """Whether ``key`` is another node's key that a deferred/immediate subscription covers."""
        hit = self._awaited.get(key)
        if hit is None:
            hit = not key.startswith(self.prefix + "/") and any(
                topics.matches(e, key) for e in self.groups
            )
            self._awaited[key] = hit
        return hit
