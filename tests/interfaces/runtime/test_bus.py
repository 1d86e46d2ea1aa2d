"""The Bus on both transports: delivery, sequence numbers, key-space rule, invalid input."""

from __future__ import annotations

import json
import pickle
import time
from collections.abc import Iterator

import pytest

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import Heartbeat, StateEstimate, TickDone, json_schema
from interfaces.runtime.bus import Bus
from interfaces.runtime.recent import archived_key, fetch_recent, recover
from interfaces.runtime.transport import InprocNetwork
from interfaces.runtime.zenoh_transport import ZenohSettings, ZenohTransport
from tests.conftest import settle

M = "bt"


def _hb(t: float) -> Heartbeat:
    return Heartbeat(sender="x", t_sim=t, node="sc1", apps=["nav"], k=int(t))


@pytest.fixture(params=["inproc", "zenoh"])
def pair(request: pytest.FixtureRequest, free_port: int) -> Iterator[tuple[Bus, Bus, object]]:
    """Two buses (sc1, sc2) and a raw injector transport on the chosen transport."""
    if request.param == "inproc":
        net = InprocNetwork()
        a, b, raw = net.endpoint(), net.endpoint(), net.endpoint()
    else:
        ep = f"tcp/127.0.0.1:{free_port}"
        a = ZenohTransport(ZenohSettings.hub(ep))
        b = ZenohTransport(ZenohSettings(connect=(ep,)))
        raw = ZenohTransport(ZenohSettings(connect=(ep,)))
    bus_a, bus_b = Bus("sc1", M, a), Bus("sc2", M, b)
    yield bus_a, bus_b, raw
    for t in (raw, b, a):
        t.close()


def test_delivery_order_sequence_and_validation(pair) -> None:  # noqa: ANN001
    bus_a, bus_b, raw = pair
    got: list[Heartbeat] = []
    key = topics.key(M, "sc1", "exec", "heartbeat")
    bus_b.subscribe(key, Heartbeat, got.append)
    time.sleep(0.3)  # subscription propagation (Zenoh)
    for t in (2.0, 1.0, 3.0):
        bus_a.publish(key, _hb(t))
    # hostile input: garbage, wrong schema, NaN, oversize; then a valid message again
    raw.publish(key, "Heartbeat", b"\x00not json")
    raw.publish(key, "Heartbeat", json.dumps({"sender": "sc1", "t_sim": 1.0}).encode())
    raw.publish(key, "Heartbeat",
                b'{"sender":"sc1","seq":9,"t_sim":NaN,"node":"a","apps":[],"k":0}')
    raw.publish(key, "Heartbeat", b" " * (2 << 20))
    bus_a.publish(key, _hb(4.0))
    settle(lambda: bus_b.wait_for({key: 4}, 0.01) == [] and bus_b.stats.invalid_dropped == 4)
    assert bus_b.stats.invalid_dropped == 4
    assert bus_b.dispatch(t_now=10.0) == 4
    assert [m.t_sim for m in got] == [1.0, 2.0, 3.0, 4.0]  # sorted by send time
    assert [m.seq for m in got] == [2, 1, 3, 4]  # per-key sequence count from the publisher
    assert all(m.sender == "sc1" for m in got)


def test_messages_from_other_nodes_wait_one_tick(pair) -> None:  # noqa: ANN001
    bus_a, bus_b, _ = pair
    got: list[Heartbeat] = []
    key = topics.key(M, "sc1", "exec", "heartbeat")
    bus_b.subscribe(key, Heartbeat, got.append)
    time.sleep(0.3)
    bus_a.publish(key, _hb(5.0))
    settle(lambda: bus_b.wait_for({key: 1}, 0.01) == [])
    assert bus_b.dispatch(5.0) == 0  # sent in the same tick: not yet due
    assert bus_b.dispatch(5.5) == 1


def test_key_space_is_enforced_and_schemas_served(pair) -> None:  # noqa: ANN001
    bus_a, bus_b, _ = pair
    with pytest.raises(ValueError, match="may not publish"):
        bus_a.publish(topics.key(M, "sc2", "nav", "estimate"), _hb(0.0))
    bus_a.serve_schemas()
    time.sleep(0.3)
    replies = bus_b.transport.query(f"{topics.node_prefix(M, 'sc1')}/schema/StateEstimate")
    assert replies and json.loads(replies[0][1]) == json_schema(StateEstimate)


def test_local_delivery_same_tick() -> None:
    net = InprocNetwork()
    bus = Bus("sc1", M, net.endpoint())
    got: list[Heartbeat] = []
    key = topics.key(M, "sc1", "exec", "heartbeat")
    bus.subscribe(key, Heartbeat, got.append)
    bus.publish(key, _hb(1.0))
    assert bus.dispatch(1.0) == 1 and got[0].seq == 1


def test_in_process_messages_skip_admission_raw_bytes_do_not() -> None:
    """The lean in-process path: a message another Bus of the process made is delivered without
    the admission checks (it cannot fail them); raw bytes on the same network are still
    validated and admitted, and a forged one is refused."""
    net = InprocNetwork()
    bus_a, bus_b, raw = Bus("sc1", M, net.endpoint()), Bus("sc2", M, net.endpoint()), \
        net.endpoint()
    got: list[Heartbeat] = []
    key = topics.key(M, "sc1", "exec", "heartbeat")
    bus_b.subscribe(key, Heartbeat, got.append)
    checked: list[str] = []
    check = bus_b.admission.check
    bus_b.admission.check = lambda k, m, p: checked.append(k) or check(k, m, p)  # type: ignore
    bus_a.publish(key, _hb(1.0))
    forged = _hb(1.5).model_dump() | {"sender": "sc3", "seq": 2}
    raw.publish(key, "Heartbeat", json.dumps(forged).encode())  # another node's name: refused
    genuine = _hb(2.0).model_dump() | {"sender": "sc1", "seq": 2}
    raw.publish(key, "Heartbeat", json.dumps(genuine).encode())
    assert checked == [key, key]  # only the two raw samples were held to admission
    assert bus_b.stats.received == 3 and bus_b.stats.refused == 1
    assert dict(bus_b.admission.refused) == {"sender": 1}
    assert bus_b.admission.highest_seq[key] == 2  # the barrier saw both genuine messages
    assert bus_b.dispatch(10.0) == 2 and [m.t_sim for m in got] == [1.0, 2.0]


def test_a_message_seen_before_is_a_duplicate_and_a_fresh_start_counts_from_one(
        pair) -> None:  # noqa: ANN001
    """A number already seen is dropped as a duplicate (counted apart, not refused), a 1 too;
    a 1 after the publisher's liveliness came back starts the count anew."""
    bus_a, bus_b, raw = pair
    key = topics.key(M, "sc1", "exec", "heartbeat")
    got: list[Heartbeat] = []
    bus_b.subscribe(key, Heartbeat, got.append)
    time.sleep(0.3)

    def send(seq: int, t: float) -> None:
        raw.publish(key, "Heartbeat", json.dumps(
            {"sender": "sc1", "seq": seq, "t_sim": t, "node": "sc1", "apps": [], "k": 0}).encode())

    for seq, t in ((1, 1.0), (2, 2.0), (2, 2.0), (1, 1.0), (3, 3.0)):
        send(seq, t)  # 2 and 1 again (a restored publisher, a resend): dropped
    settle(lambda: bus_b.stats.received == 5)
    assert bus_b.admission.duplicates == 2 and bus_b.stats.refused == 0
    assert bus_b.admission.highest_seq[key] == 3
    bus_b.admission.restarted(topics.node_prefix(M, "sc1") + "/")  # its token came back
    send(1, 4.0)  # numbered from 1 again: taken
    send(1, 4.0)  # and the same 1 again is a duplicate
    settle(lambda: bus_b.stats.received == 7)
    assert bus_b.admission.duplicates == 3
    assert bus_b.dispatch(10.0) == 4
    assert [(m.seq, m.t_sim) for m in got] == [(1, 1.0), (2, 2.0), (3, 3.0), (1, 4.0)]


def test_what_a_node_missed_is_sent_again_on_request(pair) -> None:  # noqa: ANN001
    """A node that subscribed late (as one restarted while the others ran on) asks the
    publisher for what it sent in its last ticks and takes it in; what it holds already is a
    duplicate; older ticks than the publisher keeps are gone, once the run's recorder said
    it archived them (until then they are kept for it: test_recent.py)."""
    bus_a, bus_b, raw = pair
    key = topics.key(M, "sc1", "exec", "heartbeat")
    bus_a.recent.keep(2)
    bus_a.serve_recent()
    time.sleep(0.3)  # its queryables known on the network
    raw.notify(archived_key(M, "sc1", 10_000_000_000))  # the recorder archived up to 10 s
    time.sleep(0.3)
    for t in (1.0, 2.0, 3.0):  # three ticks; sc1 keeps the last two
        bus_a.publish(key, _hb(t))
        bus_a.published_since_last()
    got: list[Heartbeat] = []
    bus_b.subscribe(key, Heartbeat, got.append)
    time.sleep(0.3)
    assert bus_b.wait_for({key: 3}, 0.01) == [key]  # announced, never came
    assert recover(bus_b, [key]) == 2
    assert bus_b.wait_for({key: 3}, 0.01) == []
    assert recover(bus_b, [key]) == 0 and bus_b.admission.duplicates == 2  # held already
    assert bus_b.dispatch(10.0) == 2 and [m.t_sim for m in got] == [2.0, 3.0]
    raw.serve(topics.recent_queryable(M, "sc3"), lambda _k: b'[["x"]]')  # a broken answer
    time.sleep(0.3)
    assert fetch_recent(bus_b, "sc3") == [] and bus_b.stats.invalid_dropped == 1


@pytest.mark.parametrize("restored", [False, True])
def test_an_answer_sent_again_brings_its_ticks_messages_again(restored: bool) -> None:
    """The sim did not get a node's answer to a tick (lost with the network, or with the
    process killed before its transport sent it, ``restored`` from its store of that tick):
    the node sends the tick's messages again, as they were, then the answer; not the answer
    to the tick before."""
    net = InprocNetwork()
    bus, raw = Bus("sc1", M, net.endpoint()), net.endpoint()
    seen: list[tuple[str, int]] = []
    raw.subscribe(f"insp/{M}/sc/1/**", lambda k, _t, p: seen.append(
        (k.rsplit("/", 1)[-1], json.loads(p)["seq"])))
    done_key, beat = cat.TICK_DONE.key(M, "sc1"), topics.key(M, "sc1", "exec", "heartbeat")
    for k in (1, 2):
        bus.publish(beat, _hb(float(k)))
        done = TickDone(sender="sc1", t_sim=float(k), k=k, published=bus.published_since_last())
        bus.publish(done_key, done, announce=False)
    if restored:
        bus.recent.restore(pickle.loads(pickle.dumps(bus.recent.checkpoint())))
    seen.clear()
    bus.send_again(done_key, done)
    assert seen == [("heartbeat", 2), ("tick_done", 2)]
