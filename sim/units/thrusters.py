"""The thrusters: each observer's body-fixed thruster pairs (``sim/actuators.py``,
``ThrusterBank``), fired by its flight software's ``ThrustCommand``.

A command is realised when it arrives, over its whole duration (minimum impulse bit and noise
on its impulse), and its average force acts on the truth until the duration ends
(``sim/hardware.py``: the dynamics reads it every tick).
"""

from __future__ import annotations

from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import ThrustCommand
from sim.units.unit import Command, Unit


class Thrusters(Unit):
    NAME = "thrusters"
    COMMANDS = (Command(cat.THRUST, "on_command"),)

    def on_command(self, index: int, msg: ThrustCommand) -> None:
        """Fire observer ``index``'s (0-based) thrusters: ``msg.force_body_n`` (N, body axes)
        for ``msg.duration_s`` (s) from ``msg.t_sim`` (s)."""
        self.ctx.hardware.command_thrust(index, msg.force_body_n, msg.duration_s, msg.t_sim)
