"""Software fault injection (test harness): the faults of a scenario that live in a
spacecraft's own software rather than in its hardware.

``faulty_data`` (docs/contracts.md): the spacecraft reports a corrupted information cost — its H_i
multiplied by ``magnitude`` while the fault is active — whereas the observations it shares stay
as measured.  The spacecraft's builder (``fsw/spacecraft.py``) hooks the factor into the infocost
app's output; the app's logic does not know about faults.
"""

from __future__ import annotations

from collections.abc import Callable

from faults.schedule import SOFTWARE_KINDS, switched_on
from interfaces.contracts.scenario import Scenario


def reported_h_factor(scenario: Scenario, spacecraft: int) -> Callable[[float], float]:
    """Factor applied at time t (s) to the H_i that ``spacecraft`` reports: the product of the
    magnitudes of its ``faulty_data`` faults active at t (1.0 when healthy)."""
    faults = [f for f in scenario.faults
              if f.kind in SOFTWARE_KINDS and f.spacecraft == spacecraft]

    def factor(t: float) -> float:
        out = 1.0
        for f in faults:
            if switched_on(f, t):
                out *= float(f.magnitude or 1.0)
        return out

    return factor
