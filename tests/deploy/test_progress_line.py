"""The launcher's progress line (deploy/progress_line.py): no speed and no end before the
first simulated second, never NaN; after it, the speed and the time left at that speed."""

from __future__ import annotations

import pytest

from deploy.progress_line import progress_line


@pytest.mark.parametrize(("t_sim_s", "duration_s", "wall_s"), [
    (0.0, 200.0, 0.0), (0.0, 200.0, 60.0), (0.4, 200.0, 60.0), (0.0, 0.0, 5.0)])
def test_before_the_first_simulated_second_speed_and_end_are_unknown(
        t_sim_s: float, duration_s: float, wall_s: float) -> None:
    line = progress_line(t_sim_s, duration_s, wall_s)
    assert "nan" not in line.lower() and "inf" not in line.lower()
    assert line.endswith("--x real time  ETA --")


@pytest.mark.parametrize(("t_sim_s", "wall_s", "speed", "left_s"), [
    (100.0, 10.0, "10x", "10 s"),      # half done in 10 s: 10 s more
    (50.0, 20.0, "2.5x", "60 s"),      # a quarter in 20 s: three quarters in 60 s
    (2.0, 4.0, "0.50x", "396 s"),      # 2 s of 200 in 4 s: 198 s more at 0.5×
    (200.0, 5.0, "40x", "0 s"),
])
def test_the_speed_and_the_time_left_at_that_speed(t_sim_s: float, wall_s: float, speed: str,
                                                    left_s: str) -> None:
    line = progress_line(t_sim_s, 200.0, wall_s)
    assert line.startswith(f"t_sim {t_sim_s:7.1f} / 200 s (")
    assert line.endswith(f"  {speed} real time  ETA {left_s}")
