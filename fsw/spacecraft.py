"""One spacecraft's flight software: its apps (``interfaces/contracts/topology.py``,
``SPACECRAFT_APPS``) on one executive, with the software faults the scenario injects."""

from __future__ import annotations

from faults.software import reported_h_factor
from fsw.apps.infocost import InfoCostApp
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topology import Node
from interfaces.runtime.assembly import build_executive
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive


def executive(node: Node, bus: Bus, scenario: Scenario) -> Executive:
    """The executive of spacecraft node ``node`` with every onboard app wired, and the
    software fault injection (``faulty_data``, ``faults/software.py``) hooked into its infocost
    app's output."""
    built = build_executive(node, bus, scenario)
    for app in built.apps:
        if isinstance(app, InfoCostApp) and node.spacecraft is not None:
            app.report_factor = reported_h_factor(scenario, node.spacecraft)
    return built
