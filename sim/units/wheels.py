"""The reaction wheels: each observer's three body-axis wheels (``sim/actuators.py``,
``WheelArray``), driven by its flight software's ``WheelCommand``.

A torque is held from its command until the next one, at most
``sim.hardware.WHEEL_COMMAND_TIMEOUT_S``, and realised within the wheels' torque and momentum
limits as the dynamics integrates the attitude (``sim/hardware.py``).
"""

from __future__ import annotations

from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import WheelCommand
from sim.units.unit import Command, Unit


class Wheels(Unit):
    NAME = "wheels"
    COMMANDS = (Command(cat.WHEELS, "on_command"),)

    def on_command(self, index: int, msg: WheelCommand) -> None:
        """Hold observer ``index``'s (0-based) wheel torque ``msg.torque_body_nm`` (N·m, body
        axes) from ``msg.t_sim`` (s)."""
        self.ctx.hardware.command_wheels(index, msg.torque_body_nm, msg.t_sim)
