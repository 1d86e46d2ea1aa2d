"""The link faults (links/faults.py): a link fault acts on the messages sent in [start, end), a
cut on every link of its spacecraft, a packet loss with its own draws on the faulty
spacecraft's links only."""

from __future__ import annotations

import math

from interfaces.contracts.scenario import Fault
from links.faults import LinkCutWindow, LinkFaults, end_s


def test_a_fault_without_an_end_never_ends() -> None:
    f = Fault(spacecraft=1, kind="link_loss", start_s=0.8, end_s=1.0)
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
