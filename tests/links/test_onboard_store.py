"""The onboard store and its dump (links/onboard_store.py) against hand-computed
times: a dump at the stated rate in priority order, overflow by the stated rule with every
message accounted for, a lost transmission sent again, and results that do not depend on how
often the store is asked."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import pytest

from interfaces.contracts.messages import Heartbeat, Message
from links.onboard_store import RETRY_S, OnboardStore, message_bytes

RATE_BPS = 8000.0
"""1000 bytes per second: a message of s bytes takes s ms on the air."""


@dataclass
class FakeLink:
    """A downlink in contact over ``windows``, up there except over ``down``; ``losses``:
    the transmissions (by start time) that are lost."""

    windows: list[tuple[float, float]]
    down: list[tuple[float, float]] = field(default_factory=list)
    losses: set[float] = field(default_factory=set)
    starts: list[float] = field(default_factory=list)

    def _contact(self, t: float) -> bool:
        return any(a <= t < b for a, b in self.windows)

    def up(self, t_s: float) -> bool:
        return self._contact(t_s) and not any(a <= t_s < b for a, b in self.down)

    def lost(self, t_s: float) -> bool:
        self.starts.append(t_s)
        return round(t_s, 6) in self.losses

    def next_contact(self, t_s: float) -> float:
        if self._contact(t_s):
            return t_s
        return min((a for a, _ in self.windows if a > t_s), default=math.inf)


def _msg(t: float, seq: int = 1) -> Message:
    return Heartbeat(sender="sc1", seq=seq, t_sim=t, node="sc1", apps=["nav"], k=0,
                     t_wall=1.7e9 + t)


def _offer(store: OnboardStore, t: float, topic: str, priority: int, seq: int = 1) -> Message:
    msg = _msg(t, seq)
    store.offer((topic, t), msg, topic, priority)
    return msg


def test_a_message_is_sized_without_its_wall_clock() -> None:
    a, b = _msg(1.0), _msg(1.0).model_copy(update={"t_wall": 123.456789012})
    assert message_bytes(a) == message_bytes(b) == len(a.model_dump_json(exclude={"t_wall"}))


def test_the_dump_starts_at_acquisition_at_the_rate_highest_priority_first() -> None:
    store = OnboardStore("sc1", 10**6, RATE_BPS)
    size = message_bytes(_msg(10.0))
    _offer(store, 10.0, "exec/heartbeat", 2)
    _offer(store, 20.0, "nav/estimate", 1)
    _offer(store, 30.0, "infocost/telemetry", 0)
    got = store.advance(1000.0, FakeLink([(100.0, 200.0)]))
    air = size / 1000.0  # s
    assert [env for _, env in got] == [("infocost/telemetry", 30.0), ("nav/estimate", 20.0),
                                       ("exec/heartbeat", 10.0)]
    assert [t for t, _ in got] == pytest.approx([100.0 + air, 100.0 + 2 * air, 100.0 + 3 * air])
    c = store.counter
    assert (c.stored, c.dumped, c.onboard, c.overflow) == (3, 3, 0, 0)
    assert c.dumped_bytes == c.stored_bytes == 3 * size


def test_in_contact_a_message_goes_down_as_it_is_sent() -> None:
    store = OnboardStore("sc1", 10**6, RATE_BPS)
    _offer(store, 150.0, "nav/estimate", 1)
    (t, _), = store.advance(1000.0, FakeLink([(100.0, 200.0)]))
    assert t == pytest.approx(150.0 + message_bytes(_msg(150.0)) / 1000.0)


def test_a_full_store_evicts_lower_priorities_oldest_first_and_refuses_what_cannot_fit() -> None:
    size = message_bytes(_msg(1.0))
    store = OnboardStore("sc1", 3 * size, RATE_BPS)
    for k, t in enumerate((1.0, 2.0)):
        _offer(store, t, "exec/heartbeat", 2, seq=k + 1)
    _offer(store, 3.0, "nav/estimate", 1)
    _offer(store, 4.0, "infocost/telemetry", 0)  # evicts the heartbeat of t = 1
    _offer(store, 5.0, "exec/heartbeat", 2, seq=3)  # nothing below it: refused
    _offer(store, 6.0, "infocost/telemetry", 0, seq=2)  # evicts the heartbeat of t = 2
    _offer(store, 7.0, "infocost/telemetry", 0, seq=3)  # evicts the nav estimate
    _offer(store, 8.0, "nav/estimate", 1, seq=2)  # only priority 0 aboard: refused
    link = FakeLink([(100.0, 200.0)])
    assert store.advance(50.0, link) == []
    c = store.counter
    assert (c.stored, c.overflow, c.onboard, c.dumped) == (6, 5, 3, 0)
    assert 8 == c.dumped + c.onboard + c.overflow  # every message offered is accounted for
    runs = [(r.topic, r.first_s, r.last_s, r.count) for r in c.overflow_runs]
    assert runs == [("exec/heartbeat", 1.0, 5.0, 3), ("nav/estimate", 3.0, 8.0, 2)]
    dumped = store.advance(math.inf, link)
    assert [env for _, env in dumped] == [("infocost/telemetry", t) for t in (4.0, 6.0, 7.0)]


def test_a_lost_transmission_is_sent_again_first() -> None:
    store = OnboardStore("sc1", 10**6, RATE_BPS)
    _offer(store, 10.0, "nav/estimate", 1)
    _offer(store, 11.0, "nav/estimate", 1, seq=2)
    link = FakeLink([(100.0, 200.0)], losses={100.0})
    got = store.advance(1000.0, link)
    air = message_bytes(_msg(10.0)) / 1000.0
    assert [env for _, env in got] == [("nav/estimate", 10.0), ("nav/estimate", 11.0)]
    assert [t for t, _ in got] == pytest.approx([100.0 + 2 * air, 100.0 + 3 * air])
    assert store.counter.retransmitted == 1 and link.starts[:2] == pytest.approx([100.0,
                                                                                   100.0 + air])


def test_in_a_pass_with_the_link_down_the_radio_tries_every_retry_interval() -> None:
    store = OnboardStore("sc1", 10**6, RATE_BPS)
    _offer(store, 10.0, "nav/estimate", 1)
    (t, _), = store.advance(1000.0, FakeLink([(100.0, 200.0)], down=[(100.0, 102.5)]))
    assert t == pytest.approx(100.0 + 3 * RETRY_S + message_bytes(_msg(10.0)) / 1000.0)


def test_what_is_dumped_when_does_not_depend_on_how_often_the_store_is_asked() -> None:
    def run(step: float) -> list[tuple[float, object]]:
        store = OnboardStore("sc1", 20 * message_bytes(_msg(1.0)), RATE_BPS)
        link = FakeLink([(30.0, 45.0), (80.0, 90.0)], losses={30.0, 81.0})
        out: list[tuple[float, object]] = []
        t, k = 0.0, 0
        while t < 120.0:
            t += step
            while k < 100 and k < t:  # every message sent before the horizon is offered
                _offer(store, float(k), ("nav/estimate", "exec/heartbeat")[k % 2], k % 2 * 2,
                       seq=k + 1)
                k += 1
            out += store.advance(t, link)
        return out

    assert run(0.1) == run(1.0) == run(7.0)
