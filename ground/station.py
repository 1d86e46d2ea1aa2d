"""The ground station: the central agent's apps on one executive."""

from __future__ import annotations

import logging

from ground.apps.baselines import BaselinesApp
from ground.apps.fdir import FdirApp
from ground.apps.planner import MissionPlanner
from ground.apps.telemetry import TelemetryMonitor
from interfaces.contracts import topics
from interfaces.contracts.rng import stream
from interfaces.contracts.scenario import Scenario
from interfaces.runtime.app import App, AppContext
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive

APPS: tuple[type[App], ...] = (MissionPlanner, TelemetryMonitor, FdirApp, BaselinesApp)


def ground_executive(bus: Bus, scenario: Scenario) -> Executive:
    log = logging.getLogger("insp.ground")
    ctx = AppContext(bus=bus, scenario=scenario, node=topics.GROUND, spacecraft=None,
                     rng=stream(scenario.seed, "ground"), log=log)
    return Executive(bus, scenario, [a(ctx) for a in APPS], log=log)
