"""The application model shared by flight and ground software (docs/architecture.md,
"Runtime model").

An app declares at class level its rate group, what it subscribes to and what it publishes; the
executive wires the declarations to the bus and runs ``step(t)`` when the group is due.  Apps talk
to each other only through the bus.  Algorithms belong in pure functions (``fsw/lib``), so that
an app's step stays short.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from operator import attrgetter
from typing import ClassVar, Self

import numpy as np

from gnc.mission import MissionConstants
from interfaces.contracts.catalogue import Topic
from interfaces.contracts.messages import Message, RateGroupName
from interfaces.contracts.scenario import Scenario
from interfaces.runtime.bus import Bus

RATE_GROUPS: tuple[RateGroupName, ...] = ("high", "mid", "low")


@dataclass(frozen=True)
class AppContext:
    """What an app gets from its executive: its bus, the scenario and the constants it implies
    (computed once per node; from the scenario when not given), its node and spacecraft, its
    random stream and its logger."""

    bus: Bus
    scenario: Scenario
    node: str
    spacecraft: int | None
    rng: np.random.Generator
    log: logging.Logger
    constants: MissionConstants = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if self.constants is None:
            object.__setattr__(self, "constants", MissionConstants.of(self.scenario))

    @property
    def mission(self) -> str:
        return self.bus.mission


@dataclass(frozen=True)
class Input:
    """A subscription: messages of ``topic`` go to method ``handler`` (of the app, or dotted, of
    a part of it: ``"pipeline.observations"``).  ``every_spacecraft``: from every spacecraft;
    otherwise the key that concerns this node (its own spacecraft's, its hardware's sensors, or
    the sim's/ground's single key)."""

    topic: Topic
    handler: str
    every_spacecraft: bool = False

    @property
    def msg_type(self) -> type[Message]:
        return self.topic.type

    def key_expr(self, ctx: AppContext) -> str:
        if self.every_spacecraft:
            return self.topic.every_spacecraft(ctx.mission)
        return self.topic.key(ctx.mission, ctx.node)


@dataclass(frozen=True)
class Output:
    """A publication named ``name`` on ``topic`` (in the app's own node's key space)."""

    name: str
    topic: Topic


class App:
    """Base of every app.  Subclasses set NAME, RATE, INPUTS, OUTPUTS and implement step(), and
    declare in CRITICAL the state a restart restores (``checkpoint``, ``restore``)."""

    NAME: ClassVar[str]
    RATE: ClassVar[RateGroupName]
    INPUTS: ClassVar[tuple[Input, ...]] = ()
    OUTPUTS: ClassVar[tuple[Output, ...]] = ()
    CRITICAL: ClassVar[tuple[str, ...]] = ()
    """The attributes (dotted: of a part) that hold what the app learnt while running: written
    to the node's critical-data store at every ω_mid boundary (``interfaces.runtime.cds``) and
    restored by a restarted process, so that it goes on as if it had not stopped.  Everything
    else an app holds must be rebuilt identically from the scenario at start."""
    REBUILT: ClassVar[tuple[str, ...]] = ()
    """Attributes that change while running but are rebuilt identically on demand (caches),
    or hooks set at start: not in the store (``tests/missions/test_restore.py`` checks, after a
    real run, that every attribute that changes is in CRITICAL or here)."""

    def __init__(self, ctx: AppContext) -> None:
        self.ctx = ctx
        self.log = ctx.log.getChild(self.NAME)
        self._outputs = {o.name: (o.topic.key(ctx.mission, ctx.node), o.topic.type)
                         for o in self.OUTPUTS}

    def wire(self) -> None:
        """Subscribe the declared inputs (called once by the executive)."""
        for i in self.INPUTS:
            self.ctx.bus.subscribe(i.key_expr(self.ctx), i.msg_type, attrgetter(i.handler)(self))

    def publish(self, name: str, msg: Message) -> None:
        """Publish on a declared output; anything else is a programming error."""
        key, msg_type = self._outputs[name]
        if not isinstance(msg, msg_type):
            raise TypeError(f"{self.NAME}.{name} publishes {msg_type.__name__}, "
                            f"got {type(msg).__name__}")
        self.ctx.bus.publish(key, msg)

    def step(self, t: float) -> None:
        """Run one cycle at simulation time ``t`` (s)."""
        raise NotImplementedError

    @classmethod
    def step_all(cls, apps: Sequence[Self], t: float) -> Sequence[Self]:
        """Run one cycle at ``t`` (s) of ``apps``, this class's apps on the spacecraft of one
        fleet (the nodes one process hosts: ``interfaces.runtime.fleet``), together, and
        return those left to their own :meth:`step`.  A class that batches over spacecraft
        (over arrays) overrides it; each member must receive, hold and publish exactly what
        its own ``step`` would (bits equal), and a member whose row fails is that
        spacecraft's failure alone: left to its own ``step``, or its error raised there.
        The default batches nothing."""
        return apps

    def checkpoint(self) -> dict[str, object]:
        """The CRITICAL attributes and the app's random stream's state (to be pickled at once:
        the values are the app's own, not copies)."""
        return {"rng": self.ctx.rng.bit_generator.state,
                "state": {name: attrgetter(name)(self) for name in self.CRITICAL}}

    def restore(self, saved: dict[str, object]) -> None:
        """Take back a ``checkpoint``.  A part the bus delivers to (a dotted input handler) is
        updated in place: its methods were subscribed at wiring."""
        state = saved["state"]
        assert isinstance(state, dict) and set(state) == set(self.CRITICAL)
        self.ctx.rng.bit_generator.state = saved["rng"]
        wired = {i.handler.split(".")[0] for i in self.INPUTS if "." in i.handler}
        for name, value in state.items():
            owner_path, _, attr = name.rpartition(".")
            owner = attrgetter(owner_path)(self) if owner_path else self
            if attr in wired and not owner_path:
                vars(getattr(self, attr)).update(vars(value))
            else:
                setattr(owner, attr, value)
