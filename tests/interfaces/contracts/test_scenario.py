"""Scenario files: defaults, clear errors for unknown keys and bad values, the shipped scenarios
(the launcher refusing a bad file: tests/missions/test_scenario_launcher.py)."""

from __future__ import annotations

import pytest

from interfaces.contracts.scenario import ScenarioError, load_scenario, parse_scenario
from tests.conftest import REPO


def test_defaults_and_pro_phasing() -> None:
    s = parse_scenario('name = "x"\nduration_s = 10\n[observers]\ncount = 4\n')
    assert s.rates.ticks_per("mid") == 10 and s.rates.ticks_per("low") == 100
    assert s.n_ticks == 101
    assert s.observers.pro(3)[1] == pytest.approx(3.141592653589793)  # 180° for sc3 of 4


@pytest.mark.parametrize("text, needle", [
    ('name = "x"\nduration_s = 10\n[orbit]\naltitud_km = 500\n', "orbit.altitud_km"),
    ('name = "x"\nduration_s = -1\n', "duration_s"),
    ('name = "x"\nduration_s = 10\n[rates]\nmid_hz = 3\n', "must divide"),
    ('name = "x"\nduration_s = 10\n[[faults]]\nspacecraft = 9\nkind = "link_loss"\nstart_s = 0\n',
     "observers.count"),
    ('name = "x"\nduration_s = 10\n[[faults]]\nspacecraft = 1\nkind = "camera_degradation"\n'
     'start_s = 0\nmagnitude = 1.5\n', "(0, 1)"),
    ('name = "x"\nduration_s = 10\n[[faults]]\nspacecraft = 1\nkind = "melted"\n'
     'start_s = 0\n', "kind"),
    ('name = "x"\nduration_s = [', "not valid TOML"),
    ('name = "x"\nduration_s = 10\n[rates]\nfdi_period_s = 2.5\n', "whole number of ω_mid"),
    ('name = "x"\nduration_s = 10\n[rates]\nfdi_period_s = 0.5\n', "rates.fdi_period_s = 0.5"),
    ('name = "x"\nduration_s = 10\n[onboard_fdir.watchpoints.pointing]\nlimit = 1\n',
     "onboard_fdir.watchpoints.pointing: unknown watchpoint"),
    ('name = "x"\nduration_s = 10\n[onboard_fdir.watchpoints.nav_nis]\nlimit = 0\n',
     "onboard_fdir.watchpoints.nav_nis: limit"),
    ('name = "x"\nduration_s = 10\n[onboard_fdir.watchpoints.nav_nis]\naction = "panic"\n',
     "onboard_fdir.watchpoints.nav_nis: action"),
    ('name = "x"\nduration_s = 10\n[onboard_fdir.watchpoints.nav_nis]\npersistance = 2\n',
     "onboard_fdir.watchpoints.nav_nis: persistance"),
    ('name = "x"\nduration_s = 10\n[onboard_fdir]\nenable = true\n', "onboard_fdir.enable"),
    ('name = "x"\nduration_s = 10\n[orbit]\ninclination_deg = 181\n', "orbit.inclination_deg"),
    ('name = "x"\nduration_s = 10\n[orbit]\nraan_deg = -5\n', "orbit.raan_deg"),
    ('name = "x"\nduration_s = 10\n[ground]\nstore_bytes = 0\n', "ground.store_bytes"),
    ('name = "x"\nduration_s = 10\n[ground]\ncontact = "passes"\n', "[[ground.stations]]"),
    ('name = "x"\nduration_s = 10\n[ground]\nepoch = 2026-03-20T12:00:00\n', "time zone"),
    ('name = "x"\nduration_s = 10\n[[ground.stations]]\nname = "gs"\nlatitude_deg = 40\n'
     'longitude_deg = 0\nelevation_mask_deg = -2\n', "ground.stations[gs].elevation_mask_deg = -2"),
    ('name = "x"\nduration_s = 10\n[[ground.stations]]\nname = "gs"\nlatitude_deg = 95\n'
     'longitude_deg = 0\n', "ground.stations[gs].latitude_deg = 95"),
    ('name = "x"\nduration_s = 10\n[neighbours]\nagree = 0\n', "neighbours.agree"),
    ('name = "x"\nduration_s = 10\n[neighbours]\naction = "panic"\n', "neighbours.action"),
    ('name = "x"\nduration_s = 10\n[neighbours]\nenable = true\n', "neighbours.enable"),
])
def test_invalid_scenarios_name_the_field(text: str, needle: str) -> None:
    with pytest.raises(ScenarioError) as e:
        parse_scenario(text, source="s.toml")
    assert needle in str(e.value) and "s.toml" in str(e.value)


def test_the_onboard_watchpoint_table_is_the_defaults_with_the_scenarios_overrides() -> None:
    s = parse_scenario('name = "x"\nduration_s = 10\n[onboard_fdir]\nenabled = true\n'
                       '[onboard_fdir.watchpoints.pointing_deg]\nlimit = 2.5\n')
    table = s.onboard_fdir.table()
    assert (table["pointing_deg"].limit, table["pointing_deg"].persistence) == (2.5, 2)
    assert table["nav_nis"] == parse_scenario('name = "x"\nduration_s = 10\n'
                                              ).onboard_fdir.table()["nav_nis"]


def test_shipped_scenarios_load() -> None:
    for path in (REPO / "deploy" / "scenarios").glob("*.toml"):
        assert load_scenario(path).name
