"""The links between the spacecraft and the ground when the ground hears only in passes
(``[ground] contact = "passes"``; docs/architecture.md, "Ground passes"): the part of a
node's channel stage (``links.channel``) that holds what crosses them.

* **Downlink** (into the ground): every message a spacecraft sends the ground goes into that
  spacecraft's onboard store (``links.onboard_store``) and reaches the ground
  when the dump brings it down, the link's delay later.  The dump's link is up in a contact
  window while the spacecraft's link is neither cut nor out of range of the target (the
  ground is reached through it); each transmission draws the link's loss.
* **Uplink** (from the ground): a message sent in contact is judged by the channel as any
  other; one sent out of contact waits on the ground until the next acquisition and is judged
  then (cut, range, loss at that time), the link's delay later.  Nothing leaves a ground that
  hears no station: it stays, counted as held.  What the ground sends at the run's start
  (t = 0: the initial assignments) was loaded aboard in a pass before the run: it is
  delivered at once, neither cut nor lost (``preloaded``; counted sent and delivered).

Both are simulated in send time, so what is delivered when does not depend on when the Bus
asks (``released``), only on the messages.
"""

from __future__ import annotations

import bisect
import dataclasses
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from gnc.passes import ContactPlan
from interfaces.contracts import catalogue
from interfaces.contracts.messages import LinkCounter, Message
from interfaces.contracts.scenario import Ground
from interfaces.contracts.timing import TIME_TOL_S
from interfaces.contracts.topics import GROUND, spacecraft_of
from links.onboard_store import OnboardStore


class Radio(Protocol):
    """What the space-ground links ask of the receiver's channel model (``links.channel``)."""

    def link_up(self, src: str, t_s: float) -> bool:
        """Whether the link from ``src`` is up at ``t_s`` (s): not cut, in range."""

    def lose(self, src: str, t_s: float) -> bool:
        """One counted transmission from ``src`` at ``t_s`` on an up link: whether it is lost."""

    def delivers(self, src: str, t_send: float) -> bool:
        """One counted message from ``src`` sent at ``t_send``, judged now: delivered?"""


@dataclass
class _DumpLink:
    """The downlink of spacecraft ``src`` as its store sees it (``onboard_store.Downlink``)."""

    radio: Radio
    src: str
    plan: ContactPlan

    def up(self, t_s: float) -> bool:
        return self.plan.in_contact(t_s) and self.radio.link_up(self.src, t_s)

    def lost(self, t_s: float) -> bool:
        return self.radio.lose(self.src, t_s)

    def next_contact(self, t_s: float) -> float:
        return self.plan.next_contact(t_s)


@dataclass(frozen=True)
class Aboard:
    """A message as a store keeps it aboard: its JSON, compressed, and its type.  Hours of
    images wait aboard between passes; as objects (lists of Python numbers) they took about
    3.4 times their JSON bytes (a 3,900 s run of the default mission under two stations' passes
    peaked at 3.4 GB).  The message that comes down is equal to the one sent, field by field
    (JSON round-trips every field, floats included)."""

    cls: type[Message]
    packed: bytes

    @classmethod
    def of(cls, msg: Message) -> Aboard:
        return cls(type(msg), zlib.compress(msg.model_dump_json().encode(), 1))

    def message(self) -> Message:
        return self.cls.model_validate_json(zlib.decompress(self.packed))


def _topic(key: str) -> str:
    """``app/name`` of a spacecraft key."""
    return "/".join(key.rsplit("/", 2)[-2:])


@dataclass(eq=False)
class SpaceGroundLink:
    """What waits on the space-ground links into node ``receiver`` (module docstring)."""

    receiver: str
    plan: ContactPlan
    ground: Ground
    delay_s: float
    stores: dict[str, OnboardStore] = field(default_factory=dict)
    """the onboard store of each spacecraft heard (receiver: the ground)"""
    uplink: list[tuple[float, tuple[float, str, int], Any]] = field(default_factory=list)
    """messages waiting on the ground: (time they go, delivery order, envelope)"""
    held: int = 0

    def takes(self, src: str, key: str, msg: Message, env: Any) -> bool:
        """Take a message from ``src`` on ``key`` that crosses a space-ground link into the
        receiver, when it must wait (a downlink always; an uplink sent out of contact).
        False: the channel judges it now, as any other."""
        if self.receiver == GROUND and spacecraft_of(src) is not None:
            self._store(src).offer(env, msg, _topic(key), catalogue.downlink_priority(key))
            env.msg = Aboard.of(msg)  # until it comes down (``released``)
            return True
        t_go = self.plan.uplinked_s(msg.t_sim)
        if src == GROUND and t_go > msg.t_sim:
            bisect.insort(self.uplink, (t_go, (msg.t_sim, key, msg.seq), env),
                          key=lambda u: u[:2])
            self.held += 1
            return True
        return False

    def preloaded(self, src: str, msg: Message) -> bool:
        """Whether ``msg`` from ``src`` was loaded aboard before the run: the ground's, sent
        at its start (``ContactPlan.uplinked_s``)."""
        return src == GROUND and self.receiver != GROUND and msg.t_sim <= TIME_TOL_S

    def released(self, t_now: float, radio: Radio) -> list[Any]:
        """The envelopes that reach the receiver by ``t_now`` (s): dumped ones in the order
        their last bits came, then uplinked ones the channel delivers at their acquisition."""
        horizon = t_now - self.delay_s + TIME_TOL_S
        dumped = sorted((t, env.order, env) for src in sorted(self.stores)
                        for t, env in self.stores[src].advance(
                            horizon, _DumpLink(radio, src, self.plan)))
        out = [env for _, _, env in dumped]
        for env in out:
            env.msg = env.msg.message()
        while self.uplink and self.uplink[0][0] < horizon:
            t_go, _, env = self.uplink.pop(0)
            if radio.delivers(env.src or "", t_go):
                out.append(env)
        return out

    def _store(self, src: str) -> OnboardStore:
        store = self.stores.get(src)
        if store is None:
            store = self.stores[src] = OnboardStore(src, self.ground.store_bytes,
                                                    self.ground.downlink_bps)
        return store

    def with_envelopes(self, fn: Callable[[Any], Any]) -> SpaceGroundLink:
        """A copy whose waiting messages carry ``fn(envelope)`` instead (a node's critical-data
        store packs them, and unpacks them on restore)."""
        return dataclasses.replace(
            self, stores={s: st.with_envelopes(fn) for s, st in self.stores.items()},
            uplink=[(t, order, fn(env)) for t, order, env in self.uplink])

    def annotate(self, counter: LinkCounter) -> LinkCounter:
        """``counter`` (a copy) with the store's or the uplink's counts of its link."""
        store = self.stores.get(counter.src)
        if store is not None:
            counter.store = store.counter.model_copy(deep=True)
        elif counter.src == GROUND:
            counter.held = self.held
        return counter
