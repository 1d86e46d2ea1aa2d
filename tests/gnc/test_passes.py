"""Ground passes (gnc/passes.py) against closed forms: an overhead pass seen from the pole, a
station beyond the orbit's reach, a geostationary target, the sidereal angle at J2000 and a
sun-synchronous node rate."""

from __future__ import annotations

import math
from datetime import UTC, datetime

import numpy as np
import pytest

from gnc.constants import MU_EARTH_M3_S2, R_EARTH_M
from gnc.passes import (
    OMEGA_EARTH_RAD_S,
    WGS84_FLATTENING,
    CircularOrbit,
    ContactPlan,
    GroundStation,
    contact_windows,
    elevation_rad,
    greenwich_sidereal_angle,
    pass_table,
    scenario_pass_table,
)
from interfaces.contracts.scenario import parse_scenario

LEO_M = R_EARTH_M + 500e3


def test_a_polar_orbit_seen_from_the_pole_passes_overhead_for_the_closed_form_arc() -> None:
    """From the pole (on the spin axis, so the Earth's turn does not move it) a polar orbit
    passes overhead once per orbit; the target is above the mask ε while its angle from the
    pole is under λ = arccos(R_p cos ε / a) - ε, R_p the polar radius: 2λ/n per pass."""
    orbit = CircularOrbit(LEO_M, math.radians(90.0), arg_lat_rad=0.3)
    mask = math.radians(10.0)
    pole = GroundStation("pole", math.radians(90.0), 0.0, mask_rad=mask)
    n = orbit.mean_motion_rad_s
    windows = contact_windows(orbit, pole, 1.234, 3 * 2 * math.pi / n)
    r_pole = R_EARTH_M * (1.0 - WGS84_FLATTENING)
    arc = math.acos(r_pole * math.cos(mask) / LEO_M) - mask
    assert len(windows) == 3
    for k, w in enumerate(windows):
        assert w.duration_s == pytest.approx(2 * arc / n, abs=5e-3)
        assert w.tca_s == pytest.approx((math.pi / 2 - 0.3 + 2 * math.pi * k) / n, abs=0.05)
        assert w.max_elevation_deg == pytest.approx(90.0, abs=1e-3)


def test_a_station_beyond_the_orbits_reach_never_sees_it_and_one_under_it_does() -> None:
    """At 80° N a 51.6° orbit at 500 km never rises above 10° (its ground track reaches 51.6°,
    and the 10° footprint's half-angle is 14°); at 45° N it does, within a day."""
    orbit = CircularOrbit(LEO_M, math.radians(51.6))
    far = GroundStation("far", math.radians(80.0), 0.0)
    near = GroundStation("near", math.radians(45.0), math.radians(7.0))
    assert contact_windows(orbit, far, 0.0, 86400.0) == []
    windows = pass_table(orbit, [far, near], 0.0, 86400.0)
    assert 2 <= len(windows) <= 8
    assert all(w.station == "near" for w in windows)
    assert [w.aos_s for w in windows] == sorted(w.aos_s for w in windows)
    mask = near.mask_rad
    overhead = 2 * (math.acos(R_EARTH_M * (1 - WGS84_FLATTENING) * math.cos(mask) / LEO_M)
                    - mask) / orbit.mean_motion_rad_s
    assert all(0.0 < w.duration_s <= 1.1 * overhead for w in windows)
    assert max(w.max_elevation_deg for w in windows) > 30.0


def test_the_pass_edges_are_at_the_mask_and_the_pass_is_above_it() -> None:
    orbit = CircularOrbit(LEO_M, math.radians(51.6), raan_rad=0.7, j2=True)
    station = GroundStation("gs", math.radians(40.0), math.radians(-4.0), 650.0,
                            math.radians(5.0))
    theta0 = greenwich_sidereal_angle(datetime(2026, 3, 1, tzinfo=UTC))
    windows = contact_windows(orbit, station, theta0, 86400.0)
    assert windows
    for w in windows:
        edges = elevation_rad(orbit, station, theta0, np.array([w.aos_s, w.los_s]))
        inside = elevation_rad(orbit, station, theta0, np.linspace(w.aos_s, w.los_s, 50)[1:-1])
        assert np.allclose(edges, station.mask_rad, atol=1e-6)
        assert np.all(inside > station.mask_rad)
        plan = ContactPlan.merged(windows)
        assert plan.in_contact(w.tca_s) and not plan.in_contact(w.los_s + 1.0)


def test_a_pass_open_at_the_start_is_clipped_there() -> None:
    """A geostationary target above a station on the equator: in view the whole run, at 90°
    all along (the target turns with the Earth)."""
    geo = (MU_EARTH_M3_S2 / OMEGA_EARTH_RAD_S ** 2) ** (1.0 / 3.0)
    orbit = CircularOrbit(geo, 0.0)
    station = GroundStation("eq", 0.0, 0.0)
    t = np.linspace(0.0, 86400.0, 97)
    assert np.allclose(elevation_rad(orbit, station, 0.0, t), math.pi / 2, atol=1e-6)
    [w] = contact_windows(orbit, station, 0.0, 3600.0)
    assert (w.aos_s, w.los_s) == (0.0, 3600.0)


def test_the_sidereal_angle_at_j2000_and_a_day_later() -> None:
    j2000 = datetime(2000, 1, 1, 12, tzinfo=UTC)
    assert math.degrees(greenwich_sidereal_angle(j2000)) == pytest.approx(280.46061837, abs=1e-9)
    later = datetime(2000, 1, 2, 12, tzinfo=UTC)
    advance = math.degrees(greenwich_sidereal_angle(later)) - 280.46061837
    assert advance == pytest.approx(360.98564736629 - 360.0, abs=1e-6)
    with pytest.raises(ValueError, match="timezone"):
        greenwich_sidereal_angle(datetime(2000, 1, 1))


def test_the_j2_node_rate_of_a_sun_synchronous_orbit_is_a_turn_a_year() -> None:
    """At 700 km a sun-synchronous orbit is inclined 98.19°: its node turns 360° per tropical
    year; without J2 the node stands still and u' = n."""
    orbit = CircularOrbit(R_EARTH_M + 700e3, math.radians(98.19), j2=True)
    raan_rate, u_rate = orbit.rates_rad_s()
    assert raan_rate == pytest.approx(2 * math.pi / (365.2422 * 86400.0), rel=0.01)
    assert abs(u_rate / orbit.mean_motion_rad_s - 1.0) < 2e-3
    plain = CircularOrbit(R_EARTH_M + 700e3, math.radians(98.19))
    assert plain.rates_rad_s() == (0.0, plain.mean_motion_rad_s)


def test_bad_spans_are_refused() -> None:
    orbit = CircularOrbit(LEO_M, 0.9)
    with pytest.raises(ValueError, match="positive"):
        contact_windows(orbit, GroundStation("gs", 0.5, 0.0), 0.0, 0.0)


def test_a_scenarios_stations_give_its_pass_table() -> None:
    """A station at 48.1° N under a 51.6° orbit at 500 km: a few passes of several minutes a
    day, each above its mask; a scenario without stations has none."""
    text = ('name = "x"\nduration_s = 86400\n[orbit]\nraan_deg = 40\n[ground]\n'
            'contact = "passes"\nepoch = 2026-06-01T00:00:00Z\n[[ground.stations]]\n'
            'name = "gs"\nlatitude_deg = 48.1\nlongitude_deg = 11.3\naltitude_m = 600\n')
    table = scenario_pass_table(parse_scenario(text))
    assert 3 <= len(table) <= 8
    assert all(w.station == "gs" and w.max_elevation_deg > 10.0 for w in table)
    assert 4 * 60 < max(w.duration_s for w in table) < 12 * 60
    assert scenario_pass_table(parse_scenario('name = "x"\nduration_s = 100\n')) == []
