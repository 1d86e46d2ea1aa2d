"""The data budget (links/data_budget.py): the visible share against the camera model's own
visibility on a sphere of POIs, the store's fluid model against hand-worked fills, the
observations' bytes as the store counts them, and the warning naming the figures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gnc.infocost import Camera, precision
from gnc.poi import sphere_pois
from interfaces.contracts.messages import PoiObservations
from links.data_budget import (
    OBSERVATIONS,
    budget,
    estimate_Bps,
    observation_bytes,
    store_peak,
    visible_fraction,
)
from links.onboard_store import message_bytes
from tests.conftest import small_scenario


@pytest.mark.parametrize(("distance_m", "half_angle_deg"),
                         [(8.0, 40.0), (20.0, 20.0), (35.0, 12.0), (60.0, 3.0), (12.0, 10.0)])
def test_the_visible_share_is_what_the_camera_model_sees_of_a_sphere(
        distance_m: float, half_angle_deg: float) -> None:
    """Pointed at the centre, the share of 20,000 Fibonacci POIs the camera model marks visible
    (front-facing, in the cone, in range) is the closed form's to the lattice's resolution."""
    pos, normal = sphere_pois(20_000, 5.0)
    cam = Camera(half_angle_rad=math.radians(half_angle_deg), max_range_m=200.0)
    p = np.array([[0.3, -0.4, distance_m]]) / np.linalg.norm([0.3, -0.4, distance_m]) * distance_m
    seen = precision(p, -p / distance_m, pos, normal, cam) > 0.0
    expected = visible_fraction(distance_m, 5.0, cam.half_angle_rad, 200.0)
    assert float(seen.mean()) == pytest.approx(expected, abs=2e-3)


def test_the_visible_share_is_half_the_sphere_far_away_and_none_out_of_range() -> None:
    assert visible_fraction(1e6, 5.0, math.radians(80.0), 2e6) == pytest.approx(0.5, abs=1e-5)
    assert visible_fraction(5.0, 5.0, 0.5, 200.0) == 0.0  # on the surface
    assert visible_fraction(300.0, 5.0, 0.5, 200.0) == 0.0  # beyond max_range_m


def test_the_store_fills_out_of_contact_and_drains_in_a_pass() -> None:
    """1 kB/s from 0 s, one pass 100-200 s at 80 kbit/s (10 kB/s): 100 kB aboard at AOS,
    emptied in 100/9 s, then 300 s to the end of a 500 s run: the peak is 300 kB at the end."""
    peak, after = store_peak(1000.0, ((100.0, 200.0),), 500.0, 80_000.0)
    assert (peak, after) == (pytest.approx(300_000.0), 0.0)
    # a downlink slower than the production never empties it: 100 kB + 100 s × 0.5 kB/s
    peak, after = store_peak(1000.0, ((100.0, 200.0),), 200.0, 4_000.0)
    assert (peak, after) == (pytest.approx(150_000.0), pytest.approx(150_000.0))


def test_an_observations_bytes_are_the_stores_count_of_such_a_message() -> None:
    small, large = observation_bytes(100, 5000), observation_bytes(1100, 5000)
    per_entry = (large - small) / 1000
    assert 7.0 < per_entry < 9.0  # an index step (2 bytes) and a decimal (4 bytes), in base64
    msg = PoiObservations(sender="sc1", t_sim=1234.5, spacecraft=1, image_t_s=1234.5,
                          poi=[0], precision=[1e-3])
    assert abs(observation_bytes(1, 5000) - message_bytes(msg)) < 30


def test_a_store_too_small_for_the_gap_is_warned_about_naming_the_figures() -> None:
    sc = small_scenario(duration_s=4000.0, ground={
        "contact": "passes", "store_bytes": 10_000_000, "downlink_bps": 2e6,
        "stations": [{"name": "hi", "latitude_deg": 19.0, "longitude_deg": -155.7}]},
        orbit={"raan_deg": 195.0})
    b = budget(sc)
    assert b is not None and not b.holds
    rate = estimate_Bps(sc)
    assert b.total_Bps == pytest.approx(sum(rate.values()))
    assert rate[OBSERVATIONS] > 0.9 * b.total_Bps
    (warning,) = b.warnings()
    assert "10,000,000" in warning and f"{b.peak_bytes:,.0f}" in warning
    big = budget(sc.model_copy(update={"ground": sc.ground.model_copy(
        update={"store_bytes": 8 * 2**30})}))
    assert big is not None and big.holds and big.warnings() == []
    assert budget(small_scenario()) is None  # the ground hears always


def test_passes_too_slow_to_dump_are_warned_about() -> None:
    """At 100 bit/s a pass cannot empty the store: what stays aboard after it is named."""
    sc = small_scenario(duration_s=4000.0, ground={
        "contact": "passes", "downlink_bps": 100.0,
        "stations": [{"name": "hi", "latitude_deg": 19.0, "longitude_deg": -155.7}]},
        orbit={"raan_deg": 195.0})
    b = budget(sc)
    assert b is not None and b.holds and b.aboard_after_last_pass_bytes > 0.0
    (warning,) = b.warnings()
    assert "downlink_bps = 100" in warning
    assert f"{b.aboard_after_last_pass_bytes:,.0f} bytes stay aboard" in warning
