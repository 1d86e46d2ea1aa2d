"""Channel model: range, cuts, Bernoulli and Gilbert-Elliott loss statistics, determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from interfaces.contracts.scenario import Burst, Comms, Fault, LinkCut
from links.channel import ChannelModel, Verdict, gilbert_elliott_rates
from links.truth import TruthHistory


def _channel(**comms: object) -> ChannelModel:
    ch = ChannelModel("sc2", Comms(**comms), seed=7)  # type: ignore[arg-type]
    return ch


def _place(ch: ChannelModel, t: float, r1: list[float], r2: list[float]) -> None:
    ch.truth.record(t, [1, 2], [r1, r2])


def test_range_uses_positions_at_send_time() -> None:
    ch = _channel(range_m=50.0)
    _place(ch, 0.0, [0, 0, 0], [49.0, 0, 0])
    _place(ch, 1.0, [0, 0, 0], [51.0, 0, 0])
    _place(ch, 2.0, [0, 0, 0], [10.0, 0, 0])
    assert ch.decide("sc1", 0.0) is Verdict.DELIVER
    assert ch.decide("sc1", 1.0) is Verdict.RANGE  # cut by distance
    assert ch.decide("sc1", 2.0) is Verdict.DELIVER  # restored
    c = ch.counters()[0]
    assert (c.sent, c.delivered, c.dropped_range) == (3, 2, 1)


def test_ground_is_reached_through_the_target() -> None:
    ch = ChannelModel("ground", Comms(range_m=30.0), seed=1)
    ch.truth.record(0.0, [1, 2], [[20.0, 0, 0], [0, 40.0, 0]])
    assert ch.decide("sc1", 0.0) is Verdict.DELIVER
    assert ch.decide("sc2", 0.0) is Verdict.RANGE


def test_scheduled_and_injected_cuts() -> None:
    ch = _channel(cuts=[LinkCut(a="sc1", b="sc2", start_s=1.0, end_s=2.0)])
    for t in (0.0, 1.0, 1.5, 2.0, 3.0):
        _place(ch, t, [0, 0, 0], [1, 0, 0])
    got = [ch.decide("sc1", t) for t in (0.0, 1.0, 1.5, 2.0)]
    assert got == [Verdict.DELIVER, Verdict.CUT, Verdict.CUT, Verdict.DELIVER]
    ch.cut("sc2", "*", start_s=3.0)
    assert ch.decide("sc1", 3.0) is Verdict.CUT


def _losses(ch: ChannelModel, n: int) -> np.ndarray:
    _place(ch, 0.0, [0, 0, 0], [1, 0, 0])
    return np.array([ch.decide("sc1", 0.0) is Verdict.LOSS for _ in range(n)])


def test_bernoulli_loss_rate_matches_setting() -> None:
    p, n = 0.2, 20_000
    lost = _losses(_channel(packet_loss=p), n)
    sd = math.sqrt(p * (1 - p) / n)
    assert abs(lost.mean() - p) < 4 * sd  # 4-sigma binomial bound
    # Bernoulli: no memory, P(loss | previous loss) = p as well
    cond = lost[1:][lost[:-1]].mean()
    assert abs(cond - p) < 0.03


def _burst_lengths(lost: np.ndarray) -> np.ndarray:
    edges = np.diff(np.concatenate([[0], lost.astype(int), [0]]))
    return np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)


def test_gilbert_elliott_rate_and_mean_burst_length() -> None:
    p, L, n = 0.3, 6.0, 60_000
    lost = _losses(_channel(packet_loss=p, burst=Burst(mean_length_packets=L)), n)
    bursts = _burst_lengths(lost)
    # Bursts are geometric with mean L (sd ~ L); the loss rate converges slower than Bernoulli
    # because of correlation: variance inflation ≈ (1 + ρ)/(1 - ρ) with ρ = 1 - p_gb - p_bg.
    p_gb, p_bg = gilbert_elliott_rates(p, L)
    rho = 1 - p_gb - p_bg
    sd_rate = math.sqrt(p * (1 - p) / n * (1 + rho) / (1 - rho))
    assert abs(lost.mean() - p) < 4 * sd_rate
    sd_len = math.sqrt(L * (L - 1)) / math.sqrt(len(bursts))
    assert abs(bursts.mean() - L) < 4 * sd_len
    # and clearly bursty: far longer runs than a Bernoulli channel of the same rate
    assert bursts.mean() > 3 * (1 / (1 - p))


def test_gilbert_elliott_unrealizable_is_an_error() -> None:
    with pytest.raises(ValueError, match="not realizable"):
        gilbert_elliott_rates(0.9, 1.0)


def test_same_seed_same_losses_other_seed_other_losses() -> None:
    a = _losses(_channel(packet_loss=0.3), 500)
    b = _losses(_channel(packet_loss=0.3), 500)
    c = _losses(ChannelModel("sc2", Comms(packet_loss=0.3), seed=8), 500)
    assert (a == b).all() and (a != c).any()



def test_link_faults_cut_and_add_loss_only_on_the_faulty_spacecraft() -> None:
    faults = [Fault(spacecraft=1, kind="link_loss", start_s=10.0, end_s=20.0),
              Fault(spacecraft=3, kind="packet_loss", start_s=0.0, magnitude=0.5)]
    ch = ChannelModel("sc2", Comms(), seed=7, faults=faults)
    for t in (0.0, 10.0, 20.0):
        ch.truth.record(t, [1, 2, 3], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    assert [ch.decide("sc1", t) for t in (0.0, 10.0, 19.9, 20.0)] == [
        Verdict.DELIVER, Verdict.CUT, Verdict.CUT, Verdict.DELIVER]
    lost = np.array([ch.decide("sc3", 0.0) is Verdict.LOSS for _ in range(4000)])
    assert abs(lost.mean() - 0.5) < 4 * math.sqrt(0.25 / 4000)
    assert all(ch.decide("sc1", 20.0) is Verdict.DELIVER for _ in range(200))  # sc1 unaffected
    # the nominal loss stream is untouched by a fault on another spacecraft
    a = ChannelModel("sc2", Comms(packet_loss=0.3), seed=7)
    b = ChannelModel("sc2", Comms(packet_loss=0.3), seed=7, faults=faults[1:])
    for ch_ in (a, b):
        ch_.truth.record(0.0, [1, 2, 3], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
        for _ in range(50):
            ch_.decide("sc3", 0.0)
    assert [a.decide("sc1", 0.0) for _ in range(300)] == [b.decide("sc1", 0.0) for _ in range(300)]


def test_one_truth_history_serves_every_channel_of_a_process() -> None:
    """The nodes of one process share one truth feed: the first Bus claims it, every channel
    model reads it, and history older than its horizon is forgotten (a message that old is
    dropped for range, as before the first truth)."""
    truth = TruthHistory(horizon_s=10.0)
    assert truth.claim_feed() and not truth.claim_feed()
    a = ChannelModel("sc1", Comms(range_m=50.0), seed=7, truth=truth)
    b = ChannelModel("sc2", Comms(range_m=50.0), seed=7, truth=truth)
    for t in range(0, 31):
        truth.record(float(t), [1, 2, 3], [[0, 0, 0], [40.0, 0, 0], [0, 60.0, 0]])
    assert a.decide("sc2", 30.0) is Verdict.DELIVER and a.decide("sc3", 30.0) is Verdict.RANGE
    assert b.decide("sc1", 25.5) is Verdict.DELIVER  # truth at 25 s
    assert b.decide("sc1", 19.0) is Verdict.RANGE  # older than the horizon: no truth kept
    pos = truth.positions_at(20.0)
    assert pos is not None and np.array_equal(pos["sc3"], [0.0, 60.0, 0.0])
    assert np.array_equal(pos["ground"], np.zeros(3))
