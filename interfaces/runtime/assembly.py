"""A node's executive assembled from the declared topology (``interfaces/contracts/topology.py``):
its apps resolved from their ``"module:Class"`` names, each given the node's context, in the
declared order; and the dataflow's declarations (``declarations``), gathered the same way.

The topology names flight and ground code without importing it; this is the one place that
loads it, by name, when a node is built (as a flight executive loads the apps its startup table
lists) or when the dataflow is drawn (``python -m interfaces.contracts.topology --graph``).
"""

from __future__ import annotations

import importlib
import logging
from collections.abc import Callable
from typing import Any

from gnc.mission import MissionConstants
from interfaces.contracts import catalogue as cat
from interfaces.contracts import dataflow
from interfaces.contracts.dataflow import AppSlot, Declared, Read
from interfaces.contracts.rng import stream
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topology import Node
from interfaces.runtime.app import App, AppContext
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive, TickClient

Builder = Callable[[Node, Bus, Scenario], Executive]
"""How a node's executive is built (``Node.executive``)."""


def resolve(name: str) -> Any:
    """The attribute ``"module:attribute"`` names; a clear error when there is none."""
    module, _, attribute = name.partition(":")
    try:
        return getattr(importlib.import_module(module), attribute)
    except (ImportError, AttributeError) as e:
        raise ValueError(f"the topology names {name!r}, which does not resolve: {e}") from e


def app_class(name: str) -> type[App]:
    """The app class ``"module:Class"`` names."""
    cls = resolve(name)
    if not (isinstance(cls, type) and issubclass(cls, App)):
        raise ValueError(f"the topology names {name!r} as an app, which is not an App subclass")
    return cls


def build_executive(node: Node, bus: Bus, scenario: Scenario) -> Executive:
    """``node``'s executive on ``bus``: every declared app with the node's context (its
    spacecraft, its random stream, its logger ``insp.<node>``, the mission's constants
    computed once for all its apps)."""
    log = logging.getLogger(f"insp.{node.name}")
    ctx = AppContext(bus=bus, scenario=scenario, node=node.name, spacecraft=node.spacecraft,
                     rng=stream(scenario.seed, *node.rng), log=log,
                     constants=MissionConstants.of(scenario))
    return Executive(bus, scenario, [app_class(a)(ctx) for a in node.apps], log=log)


def executive_of(node: Node, bus: Bus, scenario: Scenario) -> Executive:
    """``node``'s executive, built by the builder it declares (``Node.executive``)."""
    build: Builder = resolve(node.executive)
    return build(node, bus, scenario)


def declared_app(slot: AppSlot) -> Declared:
    """What the app ``slot`` names declares: its NAME, rate group, inputs and outputs."""
    cls = app_class(slot.name)
    return Declared(cls.NAME, slot.place, cls.RATE,
                    tuple(Read(i.topic, i.every_spacecraft) for i in cls.INPUTS),
                    tuple(o.topic for o in cls.OUTPUTS), slot.when)


def declarations() -> tuple[Declared, ...]:
    """Every reader and writer of the bus, for the dataflow (``interfaces/contracts/dataflow.py``):
    each app the topology can run, the sim (what it reads from its declaration, named by
    ``dataflow.SIM``), every node's executive (the lockstep) and its bus's channel model (the
    truth, ``interfaces/runtime/bus.py``)."""
    channel = Declared("channel", "node", reads=(Read(cat.TRUTH),))
    return (*(declared_app(s) for s in dataflow.roster()),
            dataflow.sim(resolve(dataflow.SIM).SUBSCRIBES),
            dataflow.executive(TickClient.SUBSCRIBES), channel)
