"""The onboard FDIR's pure parts (fsw/lib/onboard_fdir.py): a watchpoint trips once, on the
sample that completes its persistence, and clears on the first sample back within its limit;
each sampled value is None where it must not be judged."""

from __future__ import annotations

import math

from fsw.lib.onboard_fdir import (
    BLANK_WINDOW,
    CLASS_SEQUENCES,
    SEQUENCES,
    BlankImages,
    WatchState,
    class_sequences,
    pointing_deg,
    thrust_duty,
    watch,
)
from interfaces.contracts.messages import AttitudeEstimate, GuidanceStatus
from interfaces.contracts.scenario import Watchpoint


def test_a_watchpoint_trips_once_at_its_persistence_and_clears_once() -> None:
    wp, st = Watchpoint(limit=1.0, persistence=3), WatchState()
    # two over, one back (the count restarts), three over (trip), one more, back (clear), ...
    got = [watch(wp, st, v) for v in (2.0, 2.0, 0.5, 2.0, 2.0, 2.0, 5.0, 1.0, 0.2, 2.0)]
    assert got == [None, None, None, None, None, "trip", None, "clear", None, None]
    assert st.over == 1 and not st.tripped


def test_a_value_at_the_limit_is_within_it_and_nan_is_over() -> None:
    wp = Watchpoint(limit=1.0, persistence=1)
    assert watch(wp, WatchState(), 1.0) is None
    assert watch(wp, WatchState(), math.nan) == "trip"


def _att(mode: str, error_deg: float) -> AttitudeEstimate:
    return AttitudeEstimate(
        sender="sc1", t_sim=1.0, spacecraft=1, q_eci_body=[0, 0, 0, 1], q_lvlh_body=[0, 0, 0, 1],
        gyro_bias_radps=[0, 0, 0], sigma_att_rad=1e-4, target_lvlh_m=[0, 0, 0],
        pointing_error_rad=math.radians(error_deg), mode=mode, torque_body_nm=[0, 0, 0])  # type: ignore[arg-type]


def test_pointing_is_judged_only_once_tracking_has_settled() -> None:
    assert pointing_deg(_att("slew", 12.0), 100.0, 30.0) is None
    assert pointing_deg(_att("track", 4.0), 29.0, 30.0) is None  # the slew's overshoot
    assert pointing_deg(_att("track", 4.0), 30.0, 30.0) == 4.0


def test_thrust_duty_is_judged_only_while_holding_a_pro() -> None:
    def status(mode: str) -> GuidanceStatus:
        return GuidanceStatus(sender="sc1", t_sim=1.0, spacecraft=1, mode=mode,  # type: ignore[arg-type]
                              accel_lvlh_mps2=[1e-4, -3e-4, 0.0])
    assert thrust_duty(status("transfer"), 1e-3) is None
    assert thrust_duty(status("hold"), 1e-3) == 0.3


def test_blank_images_are_a_share_of_a_full_window() -> None:
    b = BlankImages()
    got = [b.add(0 if k % 2 else 5) for k in range(BLANK_WINDOW + 1)]
    assert got[:BLANK_WINDOW - 1] == [None] * (BLANK_WINDOW - 1)
    assert got[BLANK_WINDOW - 1] == 0.5 and got[BLANK_WINDOW] == 0.5


def test_every_sequence_a_class_starts_is_stored() -> None:
    assert class_sequences("actuator") == ("safe_hold", "request_plan")
    assert class_sequences("camera") == ("camera_off",)
    assert class_sequences("state_sensor") == ("nav_reset",)
    assert class_sequences("link") == () and class_sequences(None) == ()
    assert all(s in SEQUENCES for seqs in CLASS_SEQUENCES.values() for s in seqs)
