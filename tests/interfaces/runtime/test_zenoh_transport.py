"""The Zenoh transport's shared receiver: the nodes of one process take from Zenoh once what
several of them read, each gets every other node's message once and never its own, and a
message is validated once for all of them (``interfaces.runtime.zenoh_transport``)."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass

import pytest

from interfaces.contracts import topics
from interfaces.contracts.bundle import bundle_space
from interfaces.contracts.messages import Heartbeat
from interfaces.runtime.bus import Bus
from interfaces.runtime.zenoh_transport import SharedReceiver, ZenohSettings, ZenohTransport
from tests.conftest import settle

M = "zt"
EVERY_HEARTBEAT = topics.all_spacecraft(M, "exec", "heartbeat")


@dataclass
class Process:
    """sc1 and sc2 hosted in one process (one receiver), sc3 in another."""

    sc1: Bus
    sc2: Bus
    sc3: Bus
    receiver: SharedReceiver


@pytest.fixture
def process(free_port: int) -> Iterator[Process]:
    ep = f"tcp/127.0.0.1:{free_port}"
    outside = ZenohTransport(ZenohSettings.hub(ep))
    receiver = SharedReceiver()
    ours = [ZenohTransport(ZenohSettings(connect=(ep,)), shared=receiver, node=n)
            for n in ("sc1", "sc2")]
    yield Process(Bus("sc1", M, ours[0]), Bus("sc2", M, ours[1]), Bus("sc3", M, outside),
                  receiver)
    for t in (*ours, outside):
        t.close()


def _hb(node: str) -> Heartbeat:
    return Heartbeat(sender="x", t_sim=1.0, node=node, apps=[], k=10)


def _heard(bus: Bus) -> list[Heartbeat]:
    got: list[Heartbeat] = []
    bus.subscribe(EVERY_HEARTBEAT, Heartbeat, got.append)
    return got


def test_each_node_hears_every_other_once_and_a_message_is_validated_once(
        process: Process) -> None:
    heard = {b.node: _heard(b) for b in (process.sc1, process.sc2, process.sc3)}
    assert list(process.receiver._receivers) == [bundle_space(M), EVERY_HEARTBEAT]  # once
    assert [n for n, _ in process.receiver._receivers[EVERY_HEARTBEAT]] == ["sc1", "sc2"]
    time.sleep(0.3)  # subscription propagation
    for bus in (process.sc1, process.sc2, process.sc3):
        bus.publish(topics.key(M, bus.node, "exec", "heartbeat"), _hb(bus.node))
    keys = {f"sc{i}": topics.key(M, f"sc{i}", "exec", "heartbeat") for i in (1, 2, 3)}
    for bus in (process.sc1, process.sc2, process.sc3):
        others = {k: 1 for n, k in keys.items() if n != bus.node}
        settle(lambda b=bus, o=others: b.wait_for(o, 0.01) == [])
        bus.dispatch(t_now=5.0)
    time.sleep(0.2)  # anything delivered twice would have come by now
    for bus in (process.sc1, process.sc2, process.sc3):
        bus.dispatch(t_now=6.0)
        assert sorted(m.node for m in heard[bus.node]) == ["sc1", "sc2", "sc3"], bus.node
        assert bus.admission.duplicates == 0
    # sc3's message came over the network once and was validated once, for both
    from_sc3 = [next(m for m in heard[n] if m.node == "sc3") for n in ("sc1", "sc2")]
    assert from_sc3[0] is from_sc3[1]


def test_hostile_input_is_dropped_by_each_node(process: Process) -> None:
    heard = {b.node: _heard(b) for b in (process.sc1, process.sc2)}
    time.sleep(0.3)
    key = topics.key(M, "sc3", "exec", "heartbeat")
    process.sc3.transport.publish(key, "Heartbeat", b"\x00not json")
    process.sc3.transport.publish(key, "Heartbeat", b" " * (2 << 20))
    settle(lambda: process.sc1.stats.invalid_dropped == 2 == process.sc2.stats.invalid_dropped)
    process.sc3.publish(key, _hb("sc3"))
    settle(lambda: all(b.wait_for({key: 1}, 0.01) == [] for b in (process.sc1, process.sc2)))
    for bus in (process.sc1, process.sc2):
        assert bus.stats.invalid_dropped == 2
        bus.dispatch(t_now=5.0)
        assert [m.node for m in heard[bus.node]] == ["sc3"]


def test_a_key_one_node_reads_reaches_that_node_only(process: Process) -> None:
    own = {b.node: topics.key(M, "sc3", "exec", f"for_{b.node}") for b in
           (process.sc1, process.sc2)}
    got: dict[str, list[str]] = {"sc1": [], "sc2": []}
    for bus in (process.sc1, process.sc2):
        bus.transport.subscribe_samples(own[bus.node],
                                        lambda s, n=bus.node: got[n].append(s.key))
    time.sleep(0.3)
    for key in own.values():
        process.sc3.transport.publish(key, "Heartbeat", b"{}")
    settle(lambda: len(got["sc1"]) + len(got["sc2"]) >= 2)
    time.sleep(0.1)
    assert got == {"sc1": [own["sc1"]], "sc2": [own["sc2"]]}


def test_a_shared_session_must_name_its_node(free_port: int) -> None:
    t = ZenohTransport(ZenohSettings.hub(f"tcp/127.0.0.1:{free_port}"),
                       shared=SharedReceiver())
    try:
        with pytest.raises(ValueError, match="name its node"):
            t.subscribe_samples(EVERY_HEARTBEAT, lambda s: None)
    finally:
        t.close()


def test_a_node_whose_intake_fails_does_not_deprive_the_others(process: Process) -> None:
    got: list[str] = []

    def broken(_sample: object) -> None:
        raise RuntimeError("a bug in sc1's intake")

    process.sc1.transport.subscribe_samples(EVERY_HEARTBEAT, broken)
    process.sc2.transport.subscribe_samples(EVERY_HEARTBEAT, lambda s: got.append(s.key))
    time.sleep(0.3)
    key = topics.key(M, "sc3", "exec", "heartbeat")
    process.sc3.publish(key, _hb("sc3"))
    settle(lambda: got == [key])
    assert got == [key]


def test_a_notice_reaches_the_queryables_and_starts_no_thread(free_port: int) -> None:
    """``notify`` (the recorder's archived notices, one per node and chunk): every queryable
    it reaches hears it, and no thread is started for its replies."""
    ep = f"tcp/127.0.0.1:{free_port}"
    hub, other = ZenohTransport(ZenohSettings.hub(ep)), ZenohTransport(
        ZenohSettings(connect=(ep,)))
    try:
        heard: list[str] = []
        other.serve(f"{M}/sc1/bus/archived/*", lambda k: heard.append(k) or b"{}")
        time.sleep(0.5)
        threads = threading.active_count()
        for t_ns in range(20):
            hub.notify(f"{M}/sc1/bus/archived/{t_ns}")
        assert threading.active_count() == threads
        settle(lambda: len(heard) == 20, 5.0)
        assert sorted(heard) == sorted(f"{M}/sc1/bus/archived/{t}" for t in range(20))
    finally:
        for t in (other, hub):
            t.close()
