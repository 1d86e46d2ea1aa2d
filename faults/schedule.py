"""When each injected fault acts, and where (``faults/``: the harness).

Kinds by where they act: the sim's hardware (``hardware.py``), the links between nodes
(``links/faults.py``, applied by every receiving node's channel stage) and a spacecraft's own
software (``software.py``).  The archive holds every switch, whatever the kind (the sim
publishes them as ``FaultEvent``).

Two clocks decide: hardware and software faults switch on the tick at or after ``start_s`` and
off on the tick at or after ``end_s`` (within ``TIME_TOL_S``, so a tick time's rounding never
moves a switch by a tick); link faults act on the messages *sent* in [start_s, end_s).
"""

from __future__ import annotations

from interfaces.contracts.scenario import Fault
from interfaces.contracts.timing import TIME_TOL_S

HARDWARE_KINDS = frozenset({"thruster_bias", "pointing_actuator", "camera_degradation",
                            "camera_misalignment", "nav_sensor_bias", "camera_calibration",
                            "state_disturbance"})
"""Faults of the sim's units (and of the truth they move: ``state_disturbance``)."""
LINK_KINDS = frozenset({"link_loss", "packet_loss"})
"""Faults of a spacecraft's links (every link it has, both ways)."""
SOFTWARE_KINDS = frozenset({"faulty_data"})
"""Faults of a spacecraft's own software."""


def switched_on(fault: Fault, t_s: float) -> bool:
    """Whether a hardware or software ``fault`` is on at tick time ``t_s`` (s)."""
    return fault.start_s <= t_s + TIME_TOL_S and (
        fault.end_s is None or t_s < fault.end_s - TIME_TOL_S)
