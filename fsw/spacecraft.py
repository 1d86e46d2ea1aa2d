"""One spacecraft's flight software: its apps on one executive."""

from __future__ import annotations

import logging

from fsw.apps.attitude import AttitudeApp
from fsw.apps.camera import CameraApp
from fsw.apps.guidance import GuidanceApp
from fsw.apps.infocost import InfoCostApp
from fsw.apps.nav import NavApp
from fsw.faults import reported_h_factor
from interfaces.contracts import topics
from interfaces.contracts.rng import stream
from interfaces.contracts.scenario import Scenario
from interfaces.runtime.app import App, AppContext
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive

APPS: tuple[type[App], ...] = (AttitudeApp, NavApp, CameraApp, InfoCostApp, GuidanceApp)
"""The onboard apps, in execution order within a rate group."""


def spacecraft_executive(bus: Bus, scenario: Scenario, spacecraft: int) -> Executive:
    """The executive of spacecraft ``spacecraft`` (1-based) with every onboard app wired."""
    node = topics.sc_node(spacecraft)
    log = logging.getLogger(f"insp.{node}")
    ctx = AppContext(bus=bus, scenario=scenario, node=node, spacecraft=spacecraft,
                     rng=stream(scenario.seed, "fsw", spacecraft), log=log)
    apps = [a(ctx) for a in APPS]
    for app in apps:
        if isinstance(app, InfoCostApp):  # software fault injection (faulty_data), if any
            app.report_factor = reported_h_factor(scenario, spacecraft)
    return Executive(bus, scenario, apps, log=log)
