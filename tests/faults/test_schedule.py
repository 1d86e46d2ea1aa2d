"""When and where injected faults act (faults/schedule.py, links/faults.py): a hardware or
software fault switches on the tick at its start and off the tick at its end, whatever the
tick time's rounding; a link fault acts on the messages sent in [start, end), a cut on every
link of its spacecraft, a packet loss with its own draws on the faulty spacecraft's links
only."""

from __future__ import annotations

import math

from links.faults import LinkCutWindow, LinkFaults
from faults.schedule import HARDWARE_KINDS, LINK_KINDS, SOFTWARE_KINDS, end_s, switched_on
from interfaces.contracts.scenario import Fault


def test_every_fault_kind_acts_in_exactly_one_place() -> None:
    kinds = set(Fault.model_fields["kind"].annotation.__args__)  # type: ignore[union-attr]
    places = (HARDWARE_KINDS, LINK_KINDS, SOFTWARE_KINDS)
    assert set().union(*places) == kinds
    assert sum(len(p) for p in places) == len(kinds)


def test_a_switch_falls_on_the_tick_at_its_time_despite_rounding() -> None:
    f = Fault(spacecraft=1, kind="camera_degradation", start_s=0.8, end_s=1.0, magnitude=0.5)
    tick = [sum([0.1] * k) for k in range(13)]  # accumulated: 0.7999999999999999 at k = 8
    assert tick[8] < 0.8 and tick[10] < 1.0
    assert [k for k, t in enumerate(tick) if switched_on(f, t)] == [8, 9]
    assert end_s(f) == 1.0
    assert end_s(f.model_copy(update={"end_s": None})) == math.inf


def test_link_faults_cut_and_lose_only_the_faulty_spacecrafts_links() -> None:
    faults = [Fault(spacecraft=2, kind="link_loss", start_s=10.0, end_s=20.0),
              Fault(spacecraft=3, kind="packet_loss", start_s=0.0, magnitude=0.5)]
    links = LinkFaults("ground", seed=7, faults=faults)
    assert links.cuts() == [LinkCutWindow("sc2", 10.0, 20.0)]
    draws = [links.lost("sc3", 1.0 + 0.1 * k) for k in range(2000)]
    assert abs(sum(draws) / len(draws) - 0.5) < 0.05  # its magnitude, drawn per message
    assert not any(links.lost("sc1", 1.0 + 0.1 * k) for k in range(100))  # a healthy link
    again = LinkFaults("ground", seed=7, faults=faults)
    assert [again.lost("sc3", 1.0 + 0.1 * k) for k in range(2000)] == draws  # seeded
    assert not LinkFaults("ground", 7, [faults[1].model_copy(update={"start_s": 5.0})]
                          ).lost("sc3", 4.9)  # before its start
