"""A unit of the sim: one kind of an observer's hardware, for every observer at once, as the bus
sees it (docs/architecture.md, "The sim's units").

A unit declares at class level what it publishes (``OUTPUTS``: sensor topics of the catalogue,
one key per spacecraft), the commands it takes (``COMMANDS``: a spacecraft's command topic and
the method it goes to) and its rate group (``RATE``: it is due on the ticks of that group); the
sim wires the declarations and calls ``step`` on every tick the unit is due, in the order of its
task list (``sim/units/__init__.py``).  The algorithms live in the unit classes
(``sim/sensors.py``, ``sim/camera.py``, ``sim/actuators.py``, ``sim/hardware.py``); a unit
only builds them from the scenario, hands them the truth and publishes what they measure.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np

from gnc.mission import MissionConstants
from interfaces.contracts import topics
from interfaces.contracts.catalogue import Space, Topic
from interfaces.contracts.messages import Message, RateGroupName
from interfaces.contracts.scenario import Scenario
from interfaces.runtime.bus import Bus
from sim.attitude import AttitudeTruth
from sim.hardware import ObserverHardware


@dataclass(frozen=True)
class UnitContext:
    """What a unit gets from the sim: its bus, the scenario and the constants it implies, the
    hardware the dynamics integrates (thrusters, wheels, attitude truth) and the sim's
    logger."""

    bus: Bus
    scenario: Scenario
    constants: MissionConstants
    hardware: ObserverHardware
    log: logging.Logger

    @property
    def ids(self) -> list[int]:
        """The observers' spacecraft ids, 1..N."""
        return list(range(1, self.scenario.observers.count + 1))


@dataclass(frozen=True, eq=False)
class Sensed:
    """The truth at tick ``k`` (t = ``t_s``, s) as the units sense it: the observers' relative
    states in the target's LVLH frame (N, 6: m, m/s), their attitudes with respect to LVLH
    (N, 4, scalar last) and their attitude truth (body rates, the rate averaged over the last
    tick, R_eci_body)."""

    k: int
    t_s: float
    rel_lvlh: np.ndarray
    q_lvlh_body: np.ndarray
    attitude: AttitudeTruth


class SpacecraftCommand(Protocol):
    """What the sim checks of every command before a unit gets it (``SimNode._accept``)."""

    @property
    def sender(self) -> str: ...

    @property
    def t_sim(self) -> float: ...

    @property
    def spacecraft(self) -> int: ...


@dataclass(frozen=True)
class Command:
    """A command a unit takes: ``topic`` (a spacecraft's) from every observer, to method
    ``handler``, called with the observer's index (0-based) and the message once the sim has
    accepted it (of the current tick, from the spacecraft it names)."""

    topic: Topic
    handler: str


class Unit:
    """Base of every unit.  Subclasses set NAME, RATE, OUTPUTS and COMMANDS, build their unit
    classes from ``ctx`` and implement ``step`` (a unit without outputs, an actuator, acts
    when its commands arrive and has nothing to do on the tick)."""

    NAME: ClassVar[str]
    RATE: ClassVar[RateGroupName] = "high"
    OUTPUTS: ClassVar[tuple[Topic, ...]] = ()
    COMMANDS: ClassVar[tuple[Command, ...]] = ()

    def __init__(self, ctx: UnitContext) -> None:
        self.ctx = ctx
        self.ids = ctx.ids
        """the observers' spacecraft ids, 1..N (observer ``index`` is ``ids[index]``)"""
        self.every = ctx.scenario.rates.ticks_per(self.RATE)
        """ticks between two steps (1 for the high rate group)"""
        nodes = [topics.sc_node(i) for i in self.ids]
        self._keys = {t: [t.key(ctx.bus.mission, n) for n in nodes] for t in self.OUTPUTS}

    def __init_subclass__(cls, **kwargs: object) -> None:
        super().__init_subclass__(**kwargs)
        for t in cls.OUTPUTS:
            if t.space is not Space.SIM_HARDWARE:
                raise TypeError(f"{cls.__name__} publishes {t}, not a hardware topic")

    def due(self, k: int) -> bool:
        """Whether the unit steps on tick ``k``: every ``every`` ticks from tick 0."""
        return k % self.every == 0

    def publish(self, topic: Topic, index: int, msg: Message) -> None:
        """Publish ``msg`` on declared output ``topic`` for observer ``index`` (0-based);
        anything else is a programming error."""
        keys = self._keys.get(topic)
        if keys is None or not isinstance(msg, topic.type):
            raise TypeError(f"{self.NAME} does not publish {type(msg).__name__} on {topic}")
        self.ctx.bus.publish(keys[index], msg)

    def step(self, now: Sensed) -> None:
        """Sense the truth of tick ``now.k`` and publish the outputs (called when due)."""
