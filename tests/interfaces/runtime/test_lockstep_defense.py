"""The lockstep defends itself (issue 16): admission rules of the Bus (sender from the key space,
sane sequence numbers and dates, bounded queue), plausible ticks only, a node cut off rejoining
at the sim's present, and the barrier never waking for a message not yet queued (the sim's side,
TickDone announcing only its sender's keys: tests/sim/test_node.py).

Hostile messages are injected as raw bytes by a foreign endpoint on both transports, the way a
stranger on the network would send them."""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Iterator

import pytest

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import Heartbeat, Message, Tick, TickDone
from interfaces.runtime import admission
from interfaces.runtime.admission import Admission
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive, TickClient
from interfaces.runtime.transport import InprocNetwork
from interfaces.runtime.zenoh_transport import ZenohSettings, ZenohTransport
from tests.conftest import settle, small_scenario

M = "ld"
HB_KEY = topics.key(M, "sc1", "exec", "heartbeat")
SC2_HB = topics.key(M, "sc2", "exec", "heartbeat")


def _hb(t: float, seq: int, sender: str = "sc1") -> Heartbeat:
    return Heartbeat(sender=sender, seq=seq, t_sim=t, node="sc1", apps=[], k=seq)


def _bytes(msg: Message) -> bytes:
    return msg.model_dump_json().encode()


# --- the rules, as pure functions -----------------------------------------------------------


def test_admission_rules() -> None:
    a = Admission()
    assert a.check(HB_KEY, _hb(1.0, 1), pending=0) is None
    a.admit(HB_KEY, _hb(1.0, 1))
    assert a.check(HB_KEY, _hb(1.0, 2, sender="sc2"), 0)[0] == "sender"
    assert a.check(HB_KEY, _hb(1.0, 1 + admission.MAX_SEQ_JUMP), 0) is None
    assert a.check(HB_KEY, _hb(1.0, 2 + admission.MAX_SEQ_JUMP), 0)[0] == "sequence"
    other = topics.key(M, "sc1", "exec", "stats")
    assert a.check(other, _hb(1.0, admission.MAX_FIRST_SEQ + 1), 0)[0] == "sequence"
    assert a.check(HB_KEY, _hb(1e6, 2), 0) is None  # no clock yet: no time rule
    a.advance(100.0)
    a.advance(50.0)  # the clock never goes back
    assert a.clock_s == 100.0
    assert a.check(HB_KEY, _hb(100.0 + admission.MAX_AHEAD_S, 2), 0) is None
    assert a.check(HB_KEY, _hb(100.1 + admission.MAX_AHEAD_S, 2), 0)[0] == "time"
    assert a.check(HB_KEY, _hb(100.0, 2), admission.MAX_PENDING)[0] == "queue"
    assert a.highest_seq == {HB_KEY: 1}


# --- on a real Bus, both transports --------------------------------------------------------


@pytest.fixture(params=["inproc", "zenoh"])
def receiver(request: pytest.FixtureRequest,
             free_port: int) -> Iterator[tuple[Bus, object, list[Heartbeat]]]:
    """sc2's Bus subscribed to sc1's heartbeat, and a foreign raw endpoint."""
    if request.param == "inproc":
        net = InprocNetwork()
        mine, raw = net.endpoint(), net.endpoint()
    else:
        ep = f"tcp/127.0.0.1:{free_port}"
        mine = ZenohTransport(ZenohSettings.hub(ep))
        raw = ZenohTransport(ZenohSettings(connect=(ep,)))
    bus = Bus("sc2", M, mine)
    got: list[Heartbeat] = []
    bus.subscribe(HB_KEY, Heartbeat, got.append)
    time.sleep(0.3 if request.param == "zenoh" else 0.0)
    yield bus, raw, got
    raw.close()
    mine.close()


def test_forged_and_absurd_messages_are_refused_and_counted(receiver) -> None:  # noqa: ANN001
    bus, raw, got = receiver
    bus.dispatch(10.0)  # the bus's clock: t = 10 s
    raw.publish(HB_KEY, "Heartbeat", _bytes(_hb(10.0, 1)))
    raw.publish(HB_KEY, "Heartbeat", _bytes(_hb(10.0, 2, sender="sc3")))  # not the owner
    raw.publish(HB_KEY, "Heartbeat", _bytes(_hb(10.0, 10**30)))  # seq 1e30
    raw.publish(HB_KEY, "Heartbeat", _bytes(_hb(1e6, 3)))  # far future
    raw.publish(HB_KEY, "Heartbeat", _bytes(_hb(10.0, 2)))
    settle(lambda: bus.stats.received == 5)
    assert bus.stats.refused == 3 and bus.stats.invalid_dropped == 0
    assert dict(bus.admission.refused) == {"sender": 1, "sequence": 1, "time": 1}
    assert bus.admission.highest_seq[HB_KEY] == 2  # the barrier saw only the genuine two
    assert bus.wait_for({HB_KEY: 2}, 0.01) == []
    assert bus.dispatch(20.0) == 2 and [m.seq for m in got] == [1, 2]
    assert not bus.inbox.pending  # nothing left queued for a future that never comes


def test_barrier_never_wakes_before_the_message_is_queued() -> None:
    """With the interpreter switching threads as often as it can, a message announced by
    ``wait_for`` is always in the queue that ``dispatch`` reads next (the stale-command race:
    before the fix about 2% of these deliveries came a tick late)."""
    net = InprocNetwork()
    raw, bus = net.endpoint(), Bus("sc2", M, net.endpoint())
    got: list[Heartbeat] = []
    bus.subscribe(HB_KEY, Heartbeat, got.append)
    late, interval = 0, sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        for i in range(1, 2001):
            sender = threading.Thread(target=raw.publish,
                                      args=(HB_KEY, "Heartbeat", _bytes(_hb(float(i), i))))
            sender.start()
            bus.wait_for({HB_KEY: i}, 5.0)
            late += bus.dispatch(float(i), include_now=True) == 0
            sender.join()
            bus.dispatch(float(i), include_now=True)
    finally:
        sys.setswitchinterval(interval)
    assert late == 0 and len(got) == 2000


# --- the lockstep client and the sim ---------------------------------------------------------


def _tick(k: int, dt: float = 0.5, t: float | None = None) -> Tick:
    return Tick(sender="sim", t_sim=k * dt if t is None else t, k=k, dt_s=dt)


def test_only_plausible_ticks_run() -> None:
    sc = small_scenario("ld", duration_s=100.0)  # 2 Hz: 201 ticks
    net = InprocNetwork()
    bus, raw = Bus("sc1", M, net.endpoint()), net.endpoint()
    client = TickClient(Executive(bus, sc, []), synchronous=True)
    tick_key = cat.TICK.key(M)
    ticks = (_tick(0), _tick(1), _tick(10**6), _tick(1), _tick(0), _tick(2, t=7.0),
             _tick(2, dt=0.1), _tick(3), _tick(3 + 21), _tick(3 + 20))
    for seq, tick in enumerate(ticks, start=1):  # numbered as the sim's own ticks would be
        raw.publish(tick_key, "Tick", _bytes(tick.model_copy(update={"seq": seq})))
    assert client.executive.ticks == 4  # k = 0, 1, 3, 23 ran
    # all by the lockstep client's rules, not the bus's (the tick is its clock): outside the
    # run, going back, off the clock, and k = 24, 10.5 s ahead of t = 1.5 s; k = 1 right
    # after k = 1 is the open tick sent again for another node (one restarted): ignored
    assert dict(bus.admission.refused) == {"tick": 5} and bus.stats.refused == 5
    assert bus.admission.clock_s == 23 * 0.5
    # the first tick sets no clock; after it, at most MAX_TICK_GAP ticks and MAX_AHEAD_S
    fine = small_scenario("ld", duration_s=100.0, rates={"high_hz": 10.0})
    first = TickClient(Executive(Bus("sc2", M, net.endpoint()), fine, []), synchronous=True)
    assert first._implausible(_tick(50, dt=0.1)) == ""
    first._last_k = 50
    assert first._implausible(_tick(50 + 100, dt=0.1)) == ""
    assert "ticks after" in first._implausible(_tick(50 + 101, dt=0.1))


def test_a_node_cut_off_from_the_sim_rejoins_at_the_sims_present() -> None:
    """A node cut off from the sim while the sim flew on receives the sim's present far ahead
    once the sim is back: it rejoins there, and the ticks it still had queued belong to a lost
    epoch: dropped, not run, so they cannot set the bus's clock back behind the sim's present
    (which would refuse every later message as dated too far ahead)."""
    sc = small_scenario("ld", duration_s=400.0)  # 2 Hz
    net = InprocNetwork()
    bus, raw = Bus("sc1", M, net.endpoint()), net.endpoint()
    client = TickClient(Executive(bus, sc, []), synchronous=False)
    tick_key = cat.TICK.key(M)
    heard: list[Heartbeat] = []
    bus.subscribe(SC2_HB, Heartbeat, heard.append, immediate=True)

    def send(seq: int, k: int) -> None:
        raw.publish(tick_key, "Tick", _bytes(_tick(k).model_copy(update={"seq": seq})))

    for k in range(4):  # queued, not yet run: the node stalls before serving them
        send(k + 1, k)
    client.on_liveness(topics.SIM, False)
    client.on_liveness(topics.SIM, True)
    send(301, 300)  # the sim's present, 150 s on
    send(302, 301)
    stop = threading.Event()
    serving = threading.Thread(target=client.serve, args=(stop,))
    serving.start()
    try:
        deadline = time.monotonic() + 5.0
        while client.executive.ticks < 2 and time.monotonic() < deadline:
            time.sleep(0.01)
        # another node's message of the present is admitted, not refused as dated too far ahead
        raw.publish(SC2_HB, "Heartbeat", _bytes(_hb(150.5, 1, sender="sc2")))
    finally:
        stop.set()
        serving.join(timeout=5.0)
    assert client.executive.ticks == 2  # the stale ticks 0-3 were not run
    assert bus.admission.clock_s == 301 * 0.5
    assert len(heard) == 1 and bus.stats.refused == 0


def test_a_node_back_from_a_network_outage_goes_on_where_the_held_clock_is() -> None:
    """The router restarted while the sim held the clock: the node saw the sim lost and back,
    and the sim sends the open tick again.  A node that ran it answers it again (its first
    answer was lost with the network), without running it twice; then it goes on."""
    sc = small_scenario("ld", duration_s=400.0)  # 2 Hz
    net = InprocNetwork()
    bus, raw = Bus("sc1", M, net.endpoint()), net.endpoint()
    client = TickClient(Executive(bus, sc, []), synchronous=True)
    answers: list[TickDone] = []
    raw.subscribe(cat.TICK_DONE.key(M, "sc1"),
                  lambda _k, _t, p: answers.append(TickDone.model_validate_json(p)))
    seq = iter(range(1, 100))

    def send(k: int, rejoin: tuple[str, ...] = ()) -> None:
        tick = _tick(k).model_copy(update={"seq": next(seq), "rejoin": list(rejoin)})
        raw.publish(cat.TICK.key(M), "Tick", _bytes(tick))

    for k in range(3):
        send(k)
    client.on_liveness(topics.SIM, False)  # the router died after the node ran tick 2
    client.on_liveness(topics.SIM, True)
    send(2, ("sc1", "sc2"))  # the open tick, sent again: answered again, not run again
    send(2, ("sc2",))  # sent again for another node only: nothing
    send(3, ("sc1",))
    assert client.executive.ticks == 4 and bus.stats.refused == 0
    assert [a.k for a in answers] == [0, 1, 2, 2, 3]
    assert answers[2].published == answers[3].published


def test_a_node_the_sim_names_rejoining_takes_the_sims_present() -> None:
    """A node whose session came back before it noticed the sim's token drop (no liveliness
    event), or that ran a tick of the lost epoch after rejoining, receives the sim's present
    far ahead of its own tick: refused, unless the tick names it in ``rejoin`` (the sim lost
    it and sees it again); then the node takes that tick as its next and runs on from it."""
    sc = small_scenario("ld", duration_s=400.0)  # 2 Hz
    net = InprocNetwork()
    bus, raw = Bus("sc1", M, net.endpoint()), net.endpoint()
    client = TickClient(Executive(bus, sc, []), synchronous=False)
    tick_key = cat.TICK.key(M)
    seq = iter(range(1, 1000))

    def send(k: int, rejoin: tuple[str, ...] = ()) -> None:
        tick = _tick(k).model_copy(update={"seq": next(seq), "rejoin": list(rejoin)})
        raw.publish(tick_key, "Tick", _bytes(tick))

    def served(ticks: int) -> None:
        deadline = time.monotonic() + 5.0
        while (client.executive.ticks < ticks or not client.tick_queue.empty()) \
                and time.monotonic() < deadline:
            time.sleep(0.01)

    stop = threading.Event()
    serving = threading.Thread(target=client.serve, args=(stop,))
    serving.start()
    try:
        for k in (0, 1, 2, 500, 3):  # a lone tick far ahead is refused; the lockstep goes on
            send(k)
        served(4)
        assert client.executive.ticks == 4 and bus.admission.refused["tick"] == 1
        send(300)  # the sim's present, 150 s on, without a word: refused
        send(301, ("sc2",))  # another node rejoins: refused
        send(302, ("sc1", "sc2"))  # this one: taken
        send(303, ("sc2",))
        served(6)
    finally:
        stop.set()
        serving.join(timeout=5.0)
    assert bus.admission.refused["tick"] == 3
    assert client.executive.ticks == 6  # 0-3, then 302 and 303
    assert bus.admission.clock_s == 303 * 0.5
