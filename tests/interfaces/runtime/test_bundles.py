"""Bundles (issue 61, item 2; interfaces/contracts/bundle.py): the hardware traffic of a process
and tick as one message, taken row by row as if each row had come alone, only from the process
that hosts the row's node; on both transports."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.bundle import (
    MAX_HEADER_BYTES,
    MAX_ROWS,
    BundleError,
    bundle_key,
    decode_bundle,
    encode_bundle,
    hosted_nodes,
    is_bundle,
    raw_rows,
)
from interfaces.contracts.messages import Heartbeat, TickDone
from interfaces.runtime.bundle_out import BundleOut
from interfaces.runtime.bus import Bus
from interfaces.runtime.encoding import encode
from interfaces.runtime.transport import InprocNetwork, Sample
from interfaces.runtime.zenoh_transport import ZenohSettings, ZenohTransport
from tests.conftest import settle

M = "bn"
DONE_1, DONE_3 = cat.TICK_DONE.key(M, "sc1"), cat.TICK_DONE.key(M, "sc3")
HB_1 = cat.HEARTBEAT.key(M, "sc1")


def _done(node: str, k: int, seq: int = 0) -> TickDone:
    return TickDone(sender=node, seq=seq, t_sim=0.1 * k, k=k, published={})


# --- the wire format ---------------------------------------------------------------------------

def test_rows_come_back_as_they_went_and_the_key_names_the_process() -> None:
    rows = [(DONE_1, "TickDone", encode(_done("sc1", 3, 1))), (HB_1, "Heartbeat", b"{}"),
            (DONE_1, "TickDone", b"")]
    assert decode_bundle(encode_bundle(rows)) == rows
    assert decode_bundle(encode_bundle([])) == []
    key = bundle_key(M, ["sc1", "sc2", "sc3"])
    assert key == f"{topics.ROOT}/{M}/bundle/sc1-sc2-sc3"
    assert hosted_nodes(key) == {"sc1", "sc2", "sc3"} and hosted_nodes(DONE_1) == frozenset()
    assert is_bundle(key, "Bundle") and not is_bundle(key, "Tick") and not is_bundle(DONE_1,
                                                                                    "Bundle")
    with pytest.raises(ValueError):
        bundle_key(M, ["sc1", "router"])
    with pytest.raises(ValueError):
        bundle_key(M, [])


@pytest.mark.parametrize(("payload", "why"), [
    (b'[["k","T",0]]', "no header line"),
    (b'[["k","T",0]\n', "not JSON"),
    (b'{"k":1}\n', "list of at most"),
    (b"[" + b",".join([b'["k","T",0]'] * (MAX_ROWS + 1)) + b"]\n", "list of at most"),
    (b'[["k","T"]]\n', "a row is"),
    (b'[["","T",0]]\n', "row key"),
    (b'[["k",7,0]]\n', "row type"),
    (b'[["k","T",-1]]\n', "row length"),
    (b'[["k","T",true]]\n', "row length"),
    (b'[["k","T",2.0]]\n', "row length"),
    (b'[["k","T",3]]\n{}', "add up"),
    (b'[["k","T",1]]\n{}', "add up"),
    (b"[]\n" + b" " * (17 << 20), "exceed"),
    (b"[" + b" " * MAX_HEADER_BYTES + b"]\n", "no header line in its first"),  # not parsed
])
def test_a_malformed_bundle_is_refused_whole(payload: bytes, why: str) -> None:
    with pytest.raises(BundleError, match=why):
        decode_bundle(payload)


def test_raw_subscribers_get_the_rows_a_process_may_carry() -> None:
    key = bundle_key(M, ["sc1"])
    alias, elsewhere = DONE_1.replace("/sc/1/", "/sc/01/"), DONE_1.replace(f"/{M}/", "/other/")
    rows = [(DONE_1, "TickDone", b"{}"), (DONE_3, "TickDone", b"{}"), (HB_1, "Heartbeat", b"{}"),
            (alias, "TickDone", b"{}"), (elsewhere, "TickDone", b"{}")]
    # not sc3's, nor sc1's under a key the router would refuse it alone, nor another mission's
    assert raw_rows(key, "Bundle", encode_bundle(rows)) == [rows[0], rows[2]]
    assert raw_rows(key, "Bundle", b"garbage") == [(key, "Bundle", b"garbage")]  # as it came
    assert raw_rows(DONE_1, "TickDone", b"{}") == [(DONE_1, "TickDone", b"{}")]


# --- on the bus --------------------------------------------------------------------------------

@pytest.fixture(params=["inproc", "zenoh"])
def pair(request: pytest.FixtureRequest,
         free_port: int) -> Iterator[tuple[Bus, Bus, object, object]]:
    """sc1's bus with its process's bundle, sc2's bus, a raw injector and a raw listener, on
    the chosen transport."""
    if request.param == "inproc":
        net = InprocNetwork()
        a, b, raw, listener = net.endpoint(), net.endpoint(), net.endpoint(), net.endpoint()
    else:
        ep = f"tcp/127.0.0.1:{free_port}"
        a = ZenohTransport(ZenohSettings.hub(ep))
        b, raw, listener = (ZenohTransport(ZenohSettings(connect=(ep,))) for _ in range(3))
    bus_a = Bus("sc1", M, a, bundle=BundleOut(bundle_key(M, ["sc1"]), a))
    yield bus_a, Bus("sc2", M, b), raw, listener
    for t in (listener, raw, b, a):
        t.close()


def test_bundled_topics_wait_for_the_flush_and_arrive_as_if_alone(pair) -> None:  # noqa: ANN001
    bus_a, bus_b, _, raw = pair
    done: list[TickDone] = []
    beats: list[Heartbeat] = []
    seen: list[tuple[str, str]] = []
    bus_b.subscribe(cat.TICK_DONE.every(M), TickDone, done.append)
    bus_b.subscribe(HB_1, Heartbeat, beats.append)
    raw.subscribe(HB_1, lambda k, t, p: seen.append((k, t)))  # a raw subscriber of one key
    raw.subscribe(cat.TICK_DONE.every(M), lambda k, t, p: seen.append((k, t)))
    raw.subscribe(f"{topics.ROOT}/**/tick_done", lambda k, t, p: seen.append((k, "any")))
    raw.subscribe("**/exec/tick_done", lambda k, t, p: seen.append((k, "anywhere")))
    time.sleep(0.3)  # subscription propagation (Zenoh)
    bus_a.publish(DONE_1, _done("sc1", 1), announce=False)
    bus_a.publish(HB_1, Heartbeat(sender="sc1", t_sim=0.1, node="sc1", apps=[], k=1))
    settle(lambda: bus_b.wait_for({HB_1: 1}, 0.01) == [])
    time.sleep(0.2)
    assert bus_b.wait_for({DONE_1: 1}, 0.01) == [DONE_1]  # held in the bundle
    bus_a.flush_bundle()
    bus_a.flush_bundle()  # nothing held: nothing sent
    settle(lambda: bus_b.wait_for({DONE_1: 1}, 0.01) == [] and len(seen) == 4)
    assert bus_a.bundle is not None and bus_a.bundle.sent == 1
    assert bus_b.dispatch(1.0) == 2
    assert [(m.sender, m.seq, m.k) for m in done] == [("sc1", 1, 1)] and len(beats) == 1
    assert seen[0] == (HB_1, "Heartbeat")  # then rows, never a bundle, to every expression
    assert sorted(seen[1:]) == [(DONE_1, "TickDone"), (DONE_1, "any"), (DONE_1, "anywhere")]
    assert bus_b.stats.invalid_dropped == bus_b.stats.refused == 0


def test_a_row_only_from_its_own_process_and_a_bad_bundle_dropped(pair) -> None:  # noqa: ANN001
    _, bus_b, raw, listener = pair
    done: list[TickDone] = []
    archived: list[tuple[str, str]] = []
    bus_b.subscribe(cat.TICK_DONE.every(M), TickDone, done.append)
    listener.subscribe(topics.mission_wildcard(M), lambda k, t, p: archived.append((k, t)))
    time.sleep(0.3)
    key = bundle_key(M, ["sc1"])
    raw.publish(key, "Bundle", encode_bundle([
        (DONE_3, "TickDone", encode(_done("sc3", 1, 1))),  # sc1's process does not host sc3
        (DONE_1.replace("/sc/1/", "/sc/01/"), "TickDone",  # sc1, outside its key space
         encode(_done("sc1", 1, 1))),
        (DONE_1, "TickDone", b"\x00not json"),  # a row that is not valid: its own drop
        (DONE_1, "TickDone", encode(_done("sc1", 2, 1))),
    ]))
    raw.publish(key, "Bundle", b"[[1]]\nnot a bundle")
    settle(lambda: bus_b.stats.invalid_dropped == 2 and bus_b.stats.refused == 2)
    assert bus_b.admission.refused["stranger"] == 2
    assert bus_b.wait_for({DONE_1: 1}, 1.0) == []
    assert bus_b.dispatch(1.0) == 1 and [(m.sender, m.k) for m in done] == [("sc1", 2)]
    settle(lambda: len(archived) == 3)  # what the recorder would store: rows, the bad one whole
    assert archived == [(DONE_1, "TickDone"), (DONE_1, "TickDone"), (key, "Bundle")]


def test_a_bundle_that_does_not_parse_is_unpacked_once_for_the_process() -> None:
    net = InprocNetwork()
    buses = [Bus(n, M, net.endpoint()) for n in ("sc2", "sc3")]
    for bus in buses:
        bus.subscribe(cat.TICK_DONE.every(M), TickDone, print)
    sample = Sample(bundle_key(M, ["sc1"]), "Bundle", payload=b"[[1]]\nnot a bundle")
    for bus in buses:  # as a SharedReceiver hands one sample to each node of a process
        bus._on_bundle(sample)
    assert isinstance(sample.rows, BundleError)  # why it has none, kept for the next Bus
    assert [b.stats.invalid_dropped for b in buses] == [1, 1]  # each Bus counts its drop
