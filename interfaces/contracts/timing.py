"""Sim time's tolerance, one for the whole system.

Two sim times (s) closer than ``TIME_TOL_S`` are the same instant.  Tick times are
accumulated or multiplied multiples of dt = 1/ω_high in floating point; over missions of days
they round by about 1e-11 s, far below it, and it is far below any period the system runs
(1/ω_high is 0.1 s by default).  A switch, a deadline or a window boundary compared with it
falls on the tick it names, whatever the rounding.
"""

from __future__ import annotations

from typing import Final

TIME_TOL_S: Final[float] = 1e-9
"""Times closer than this are the same instant, s."""
