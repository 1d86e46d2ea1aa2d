"""The launcher's progress line: how far the run is, how fast it goes, when it will end.

Until the run has flown its first simulated second, its speed and end are unknown (the
processes are still starting, the first ticks are still being answered): the line says
``--`` for both rather than a speed of 0× and an end at infinity or NaN.
"""

from __future__ import annotations

FIRST_SIM_S = 1.0
"""Simulated time (s) after which the speed and the time left are estimated."""


def progress_line(t_sim_s: float, duration_s: float, wall_s: float) -> str:
    """The line for a run at ``t_sim_s`` (s simulated) of ``duration_s`` (s), ``wall_s`` (s,
    wall) after it started: the fraction done, the speed (× real time) and the time left (s,
    wall, at the speed so far)."""
    frac = min(max(t_sim_s / duration_s, 0.0), 1.0) if duration_s > 0 else 0.0
    head = f"t_sim {t_sim_s:7.1f} / {duration_s:.0f} s ({100 * frac:3.0f}%)"
    if t_sim_s < FIRST_SIM_S or wall_s <= 0:
        return f"{head}  --x real time  ETA --"
    speed = t_sim_s / wall_s
    left_s = wall_s * (1 - frac) / frac
    return f"{head}  {speed:.{_decimals(speed)}f}x real time  ETA {left_s:.0f} s"


def _decimals(speed: float) -> int:
    """Decimals that show a speed to two significant figures, at most (none from 10×)."""
    return 2 if speed < 1 else 1 if speed < 10 else 0
