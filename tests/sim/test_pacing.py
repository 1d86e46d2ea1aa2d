"""The sim's pacing (sim/pacing.py): tick times due at t / SPEED after the start, a tick held
until it is due, the answers waited for until the next tick with hard deadlines and for the
lockstep's timeout as a ceiling, falling behind logged at most every ``BEHIND_LOG_S``, and a
speed that is not positive refused."""

from __future__ import annotations

import logging
import math
import time

import pytest

from sim.pacing import BEHIND_LOG_S, Pacer

LOG = logging.getLogger("test.pacing")


def test_a_tick_is_due_at_its_sim_time_over_the_speed() -> None:
    pacer = Pacer(50.0, hard=False, log=LOG)
    pacer.start()
    t0 = time.monotonic()
    pacer.wait(1.0)  # due 20 ms after the start
    assert time.monotonic() >= pacer.due(1.0) >= t0
    assert pacer.due(10.0) - pacer.due(0.0) == pytest.approx(0.2)


def test_answers_wait_for_the_next_tick_only_with_hard_deadlines() -> None:
    hard, ceiling = Pacer(10.0, hard=True, log=LOG), Pacer(10.0, hard=False, log=LOG)
    hard.start()
    ceiling.start()
    assert hard.answer_deadline(2.0, 0.5, 60.0) == pytest.approx(hard.due(2.5))
    assert ceiling.answer_deadline(2.0, 0.5, 60.0) >= time.monotonic() + 59.0


def test_a_late_tick_slips_the_ceilings_schedule_but_not_a_hard_one() -> None:
    ceiling, hard = Pacer(1.0, hard=False, log=LOG), Pacer(1.0, hard=True, log=LOG)
    for pacer in (ceiling, hard):
        pacer.start()
        pacer._wall0 -= 100.0  # started 100 s of wall time ago: tick 3 s is 97 s late
        pacer.wait(3.0)
    assert ceiling.due(3.0) == pytest.approx(time.monotonic(), abs=0.5)  # no burst to catch up
    assert hard.due(3.0) < time.monotonic() - 90.0  # the wall clock stays the master


def test_a_pace_below_the_ceiling_is_logged_once_per_interval(
        caplog: pytest.LogCaptureFixture) -> None:
    pacer = Pacer(100.0, hard=False, log=LOG)
    pacer.start()
    pacer._mark = (time.monotonic() - BEHIND_LOG_S, 0.0)  # 10 s of wall time for 5 s of sim time
    with caplog.at_level(logging.WARNING, logger="test.pacing"):
        for t in (5.0, 5.0001, 5.0002):
            pacer.wait(t)
    below = [r.getMessage() for r in caplog.records if "below the 100x ceiling" in r.getMessage()]
    assert len(below) == 1 and below[0].startswith("0.5x real time")
    assert "results do not change" in below[0]


@pytest.mark.parametrize("speed", [0.0, -2.0, math.inf, math.nan])
def test_a_speed_that_is_not_positive_and_finite_is_refused(speed: float) -> None:
    with pytest.raises(ValueError, match="positive speed"):
        Pacer(speed, hard=False, log=LOG)


def test_a_hold_slips_the_schedule_in_either_mode() -> None:
    """A restart the sim waited for is no lateness: after the hold, the next tick is not due at
    once, even with hard deadlines (no burst of unanswered ticks)."""
    for hard in (False, True):
        pacer = Pacer(10.0, hard=hard, log=LOG)
        pacer.start()
        before = pacer.due(1.0)
        pacer.slip(30.0)
        assert pacer.due(1.0) == pytest.approx(before + 30.0)
    assert pacer.answer_deadline(1.0, 0.5, 60.0) > time.monotonic() + 29.0  # the hard one
