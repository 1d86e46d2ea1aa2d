"""The apps of each node, in execution order within a rate group, named ``"module:Class"`` so
that no contract imports flight or ground code (``interfaces/runtime/assembly.py`` resolves
them).  The topology composes the nodes from them (``interfaces/contracts/topology.py``); the
dataflow reads their declarations (``interfaces/contracts/dataflow.py``)."""

from __future__ import annotations

SPACECRAFT_APPS: tuple[str, ...] = (
    "fsw.apps.attitude:AttitudeApp",
    "fsw.apps.nav:NavApp",
    "fsw.apps.camera:CameraApp",
    "fsw.apps.infocost:InfoCostApp",
    "fsw.apps.guidance:GuidanceApp",
)
"""A spacecraft's onboard apps, in execution order within a rate group."""

ONBOARD_FDIR_APPS: tuple[str, ...] = ("fsw.apps.fdir:OnboardFdirApp",)
"""Added after them when the scenario turns the agent-level FDIR on (``[onboard_fdir]``)."""

NEIGHBOUR_APPS: tuple[str, ...] = ("fsw.apps.neighbours:NeighboursApp",)
"""Added after those when the scenario turns the neighbours' FDIR on (``[neighbours]``)."""

GROUND_APPS: tuple[str, ...] = (
    "ground.apps.planner:MissionPlanner",
    "ground.apps.telemetry:TelemetryMonitor",
    "ground.apps.fdir:FdirApp",
    "ground.apps.baselines:BaselinesApp",
)
"""The ground station's apps, in execution order within a rate group."""
