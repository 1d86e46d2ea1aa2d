"""The space-ground links with ground passes (links/space_ground.py, through the
channel stage that owns them): a downlink waits in the store for the pass and comes down at
the stated rate, an uplink sent out of contact waits on the ground for the acquisition (but
what is sent at the start was loaded before the run), and a
link cut for a whole pass keeps everything aboard for the next one, accounted for."""

from __future__ import annotations

import pytest

from gnc.passes import ContactPlan
from interfaces.contracts.messages import Heartbeat, ProAssignments
from interfaces.contracts.scenario import Comms, Ground, LinkCut, Station
from interfaces.runtime.inbox import Envelope
from links.channel import ChannelModel, TruthHistory
from links.onboard_store import message_bytes
from links.space_ground import Aboard, SpaceGroundLink

GROUND = Ground(contact="passes", downlink_bps=8000.0,
                stations=[Station(name="st", latitude_deg=48.0, longitude_deg=11.0)])
PLAN = ContactPlan(((100.0, 200.0), (300.0, 400.0)))


def _channel(receiver: str, cuts: list[LinkCut] | None = None) -> ChannelModel:
    ch = ChannelModel(receiver, Comms(range_m=100.0, cuts=cuts or []), seed=3,
                      truth=TruthHistory(horizon_s=1e4), ground=GROUND, contact=PLAN)
    for t in range(0, 500, 10):  # sc1 10 m from the target all along
        ch.truth.record(float(t), [1], [[10.0, 0.0, 0.0]])
    return ch


def _heartbeat(t: float, seq: int) -> Envelope:
    msg = Heartbeat(sender="sc1", seq=seq, t_sim=t, node="sc1", apps=[], k=0)
    return Envelope(msg, "insp/m/sc/1/exec/heartbeat", "sc1", False, [])


def _offer(ch: ChannelModel, env: Envelope) -> bool:
    return ch.transmit(env.src or "", env.key, env.msg, env) == "wait"


def test_the_downlink_waits_for_the_pass_and_comes_down_at_the_rate() -> None:
    ch = _channel("ground")
    envs = [_heartbeat(t, k + 1) for k, t in enumerate((10.0, 20.0))]
    sent = [e.msg for e in envs]
    air = message_bytes(sent[0]) / 1000.0  # s at 8 kbit/s
    assert all(_offer(ch, e) for e in envs)
    assert all(isinstance(e.msg, Aboard) for e in envs)  # kept as compressed JSON aboard
    assert ch.released(99.0) == []
    assert ch.released(100.0 + 1.5 * air) == envs[:1]
    assert ch.released(100.0 + 2.5 * air) == envs[1:]
    assert [e.msg for e in envs] == sent  # what comes down is what was sent, field by field
    (c,) = ch.counters()
    assert c.store is not None
    assert (c.sent, c.delivered, c.store.stored, c.store.dumped, c.store.onboard) == (
        2, 2, 2, 2, 0)


def test_an_uplink_out_of_contact_waits_for_the_acquisition() -> None:
    ch = _channel("sc1")
    cmd = ProAssignments(sender="ground", seq=1, t_sim=20.0, assignments=[])
    env = Envelope(cmd, "insp/m/ground/planner/assignments", "ground", False, [])
    assert ch.transmit("ground", env.key, cmd, env) == "wait"
    assert ch.released(99.9) == []
    assert ch.released(100.1) == [env]
    in_pass = cmd.model_copy(update={"t_sim": 150.0, "seq": 2})
    assert ch.transmit("ground", env.key, in_pass, env) == "deliver"  # judged at once
    (c,) = ch.counters()
    assert (c.held, c.sent, c.delivered) == (1, 2, 2)


def test_what_the_ground_sends_at_the_start_was_loaded_before_the_run() -> None:
    """The initial assignments (t = 0, out of contact here: the first pass is at 100 s) are
    aboard from the start, not held for the first pass, nor cut, nor lost; what follows at
    1 s waits for the pass."""
    ch = _channel("sc1", cuts=[LinkCut(a="sc1", b="ground", start_s=0.0, end_s=50.0)])
    cmd = ProAssignments(sender="ground", seq=1, t_sim=0.0, assignments=[])
    env = Envelope(cmd, "insp/m/ground/planner/assignments", "ground", False, [])
    assert ch.transmit("ground", env.key, cmd, env) == "deliver"
    later = cmd.model_copy(update={"t_sim": 1.0, "seq": 2})
    assert ch.transmit("ground", env.key, later, env) == "wait"
    (c,) = ch.counters()
    assert (c.held, c.sent, c.delivered, c.dropped_cut) == (1, 1, 1, 0)


def test_a_link_cut_for_a_whole_pass_keeps_the_data_for_the_next() -> None:
    ch = _channel("ground", cuts=[LinkCut(a="sc1", b="ground", start_s=0.0, end_s=250.0)])
    envs = [_heartbeat(float(t), k + 1) for k, t in enumerate(range(0, 250, 10))]
    for e in envs:
        _offer(ch, e)
    assert ch.released(299.0) == []
    (c,) = ch.counters()
    assert c.store is not None and (c.store.onboard, c.store.dumped) == (len(envs), 0)
    assert c.store.onboard_since_s == 0.0  # the oldest aboard
    got = ch.released(400.0)
    assert got == envs
    (c,) = ch.counters()
    assert c.store is not None
    assert (c.store.stored, c.store.dumped, c.store.onboard, c.store.overflow) == (
        len(envs), len(envs), 0, 0)
    assert c.store.onboard_since_s is None
    assert c.dropped_cut == 0 and c.sent == len(envs)


def test_the_contact_plan_merges_overlapping_passes_and_finds_the_next() -> None:
    from gnc.passes import ContactWindow
    plan = ContactPlan.merged([ContactWindow("a", 10.0, 20.0, 15.0, 30.0),
                               ContactWindow("b", 15.0, 30.0, 20.0, 40.0),
                               ContactWindow("a", 50.0, 60.0, 55.0, 20.0)])
    assert plan.windows == ((10.0, 30.0), (50.0, 60.0))
    assert [plan.in_contact(t) for t in (5.0, 10.0, 29.9, 30.0, 55.0)] == [
        False, True, True, False, True]
    assert [plan.next_contact(t) for t in (5.0, 12.0, 30.0, 61.0)] == pytest.approx(
        [10.0, 12.0, 50.0, float("inf")])
    assert plan.contact_end(35.0) == 60.0 and plan.contact_end(12.0) == 30.0


def test_what_waits_is_packed_and_unpacked_with_every_envelope() -> None:
    """A node's critical-data store keeps what waits on its space-ground links (Bus.checkpoint):
    the copy carries ``fn(envelope)`` and leaves the original as it was."""
    ch = _channel("ground")
    envs = [_heartbeat(t, k + 1) for k, t in enumerate((10.0, 20.0))]
    for e in envs:
        _offer(ch, e)
    ch.released(100.0)  # the first on the air
    link = ch.passes
    assert isinstance(link, SpaceGroundLink)
    packed = link.with_envelopes(lambda e: e.msg.message().seq)  # kept as sent (Aboard)
    assert packed.stores["sc1"].held() == [1, 2] and link.stores["sc1"].held() == envs
    restored = packed.with_envelopes(lambda seq: envs[seq - 1])
    assert restored.stores["sc1"].held() == envs
