"""Scenario files (TOML) as pydantic models: the contract of docs/contracts.md ("Scenario TOML"),
one file per owner of its sections (``model.py``: the whole scenario and its loaders)."""

from __future__ import annotations

from interfaces.contracts.scenario.base import Section
from interfaces.contracts.scenario.comms import Burst, Comms, LinkCut
from interfaces.contracts.scenario.faults import COMMON_MODE_KINDS, Fault, FaultKind
from interfaces.contracts.scenario.fdir import FdirSettings
from interfaces.contracts.scenario.flight import Actuators, Attitude, Guidance, Nav, Sensors
from interfaces.contracts.scenario.ground import Ground, Station
from interfaces.contracts.scenario.mission import CameraSettings, Orbit, Target
from interfaces.contracts.scenario.model import (
    Scenario,
    ScenarioError,
    load_scenario,
    parse_scenario,
    validated,
)
from interfaces.contracts.scenario.neighbours import Neighbours
from interfaces.contracts.scenario.observers import ObserverOverride, Observers, Phase
from interfaces.contracts.scenario.onboard import (
    DEFAULT_WATCHPOINTS,
    OnboardFdir,
    SequenceName,
    Watchpoint,
)
from interfaces.contracts.scenario.planning import AssignmentSettings
from interfaces.contracts.scenario.rates import Rates
from interfaces.contracts.scenario.sim import SimSettings

__all__ = [
    "Actuators", "AssignmentSettings", "Attitude", "Burst", "COMMON_MODE_KINDS", "CameraSettings",
    "Comms", "DEFAULT_WATCHPOINTS", "Fault", "FaultKind", "FdirSettings", "Ground", "Guidance",
    "LinkCut", "Nav", "Neighbours", "ObserverOverride", "Observers", "OnboardFdir", "Orbit",
    "Phase", "Rates",
    "Scenario", "ScenarioError", "Section", "Sensors", "SequenceName", "SimSettings", "Station",
    "Target", "Watchpoint", "load_scenario", "parse_scenario", "validated",
]
