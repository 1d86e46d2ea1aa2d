"""summary.json's ``ground_contact`` (harness/summary/ground_contact.py): absent for a
ground that hears continuously; with passes, the pass table of the scenario, the longest gap in
the run (checked against the windows by hand) and each spacecraft's store and held uplinks from the
ground's channel counters."""

from __future__ import annotations

import pytest

from gnc.passes import ContactPlan
from harness.summary.ground_contact import ground_contact, longest_gap
from interfaces.contracts.messages import LinkCounter, StoreCounter
from tests.conftest import small_scenario

STATION = {"name": "mid", "latitude_deg": 48.08, "longitude_deg": 11.28}


def test_continuous_contact_has_no_section() -> None:
    assert ground_contact(small_scenario(), []) is None


def test_the_longest_gap_counts_the_run_s_ends() -> None:
    plan = ContactPlan(((100.0, 200.0), (300.0, 350.0)))
    assert longest_gap(plan, 1000.0) == 650.0  # 350 s to the end
    assert longest_gap(plan, 380.0) == 100.0  # 0-100 and 200-300
    assert longest_gap(ContactPlan(()), 500.0) == 500.0


def test_the_section_holds_the_passes_and_the_stores() -> None:
    orbit = {"inclination_deg": 51.6, "raan_deg": 255.0, "arg_latitude_deg": 90.0}
    sc = small_scenario(duration_s=7000.0, orbit=orbit,
                        ground={"contact": "passes", "stations": [STATION]})
    store = StoreCounter(stored=5, dumped=4, onboard=1)
    links = [LinkCounter(src="sc1", dst="ground", store=store),
             LinkCounter(src="ground", dst="sc1", held=2),
             LinkCounter(src="sc1", dst="sc2")]
    g = ground_contact(sc, links)
    assert g is not None
    assert [p.station for p in g.passes] == ["mid", "mid"]
    (a0, l0), (a1, _) = ((p.aos_s, p.los_s) for p in g.passes)
    assert a0 < 60.0 < l0 < a1  # the scenario of the passes campaign: a pass at the start
    assert g.longest_gap_s == pytest.approx(a1 - l0, abs=1e-3)
    assert g.stores == {"sc1": store} and g.uplink_held == {"sc1": 2}
