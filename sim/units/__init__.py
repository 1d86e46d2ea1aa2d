"""The sim's hardware units, one module each (``sim/units/unit.py``: what a unit declares).

``UNITS`` is the sim's task list: every tick the sim calls the ``step`` of each unit due, in
this order, after it has published the truth of the tick; the commands go to the units that
declare them.  A new sensor is a new module here and its line in ``UNITS``.
"""

from __future__ import annotations

from sim.units.attitude_sensors import AttitudeSensors
from sim.units.camera import Camera
from sim.units.relnav import RelNav
from sim.units.thrusters import Thrusters
from sim.units.unit import Unit
from sim.units.wheels import Wheels

UNITS: tuple[type[Unit], ...] = (AttitudeSensors, Camera, RelNav, Thrusters, Wheels)
