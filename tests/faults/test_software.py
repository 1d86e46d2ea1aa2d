"""Software fault injection (faults/software.py): the factor a spacecraft's reported H_i is
multiplied by -- the product of its active ``faulty_data`` magnitudes, 1 when healthy, switched
at the fault's own ticks, and nothing from another spacecraft's faults or from hardware
faults."""

from __future__ import annotations

from faults.software import reported_h_factor
from tests.conftest import small_scenario


def test_the_factor_is_the_product_of_the_active_faulty_data_magnitudes() -> None:
    sc = small_scenario(observers={"count": 3}, faults=[
        {"spacecraft": 2, "kind": "faulty_data", "start_s": 10.0, "end_s": 20.0,
         "magnitude": 3.0},
        {"spacecraft": 2, "kind": "faulty_data", "start_s": 15.0, "magnitude": 0.5},
        {"spacecraft": 1, "kind": "faulty_data", "start_s": 0.0, "magnitude": 4.0},
        {"spacecraft": 2, "kind": "camera_degradation", "start_s": 0.0, "magnitude": 0.5},
    ])
    sc2 = reported_h_factor(sc, 2)
    assert [sc2(t) for t in (0.0, 9.5, 10.0, 14.5, 15.0, 19.5, 20.0, 40.0)] == \
        [1.0, 1.0, 3.0, 3.0, 1.5, 1.5, 0.5, 0.5]
    assert reported_h_factor(sc, 1)(5.0) == 4.0
    assert reported_h_factor(sc, 3)(15.0) == 1.0  # no fault of its own: healthy


def test_a_switch_falls_on_its_tick_whatever_the_rounding() -> None:
    """A tick time accumulated in floating point (0.1 added 100 times is not 10.0) is the
    fault's start tick, as for the hardware faults (faults/schedule.py)."""
    sc = small_scenario(faults=[{"spacecraft": 1, "kind": "faulty_data", "start_s": 10.0,
                                 "end_s": 20.0, "magnitude": 2.0}])
    t = 0.0
    for _ in range(100):
        t += 0.1
    assert t != 10.0 and reported_h_factor(sc, 1)(t) == 2.0
