"""Scenario files (TOML) as pydantic models: the contract of docs/contracts.md ("Scenario TOML").

Every section has defaults, so a scenario states only what differs.  Unknown keys are errors
(a typo must not silently fall back to a default); values are checked for range and
consistency, and errors name the file and the offending field and value, one line each
(``interfaces/contracts/errors.py``).  The command line's seed and duration are applied before
the scenario is checked (:func:`load_scenario`), so it is checked once, as the run will fly.
"""


from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path
from typing import Any

from pydantic import Field, ValidationError, model_validator

from interfaces.contracts.errors import describe
from interfaces.contracts.scenario.base import Section
from interfaces.contracts.scenario.comms import Comms
from interfaces.contracts.scenario.faults import Fault
from interfaces.contracts.scenario.fdir import FdirSettings
from interfaces.contracts.scenario.flight import Actuators, Attitude, Guidance, Nav, Sensors
from interfaces.contracts.scenario.ground import Ground
from interfaces.contracts.scenario.mission import CameraSettings, Orbit, Target
from interfaces.contracts.scenario.neighbours import Neighbours
from interfaces.contracts.scenario.observers import Observers, Phase
from interfaces.contracts.scenario.onboard import OnboardFdir
from interfaces.contracts.scenario.planning import AssignmentSettings
from interfaces.contracts.scenario.rates import Rates
from interfaces.contracts.scenario.sim import SimSettings


class Scenario(Section):
    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$")
    seed: int = Field(default=0, ge=0)
    duration_s: float = Field(gt=0.0)
    orbit: Orbit = Orbit()
    target: Target = Target()
    camera: CameraSettings = CameraSettings()
    rates: Rates = Rates()
    comms: Comms = Comms()
    observers: Observers = Observers()
    sensors: Sensors = Sensors()
    nav: Nav = Nav()
    actuators: Actuators = Actuators()
    guidance: Guidance = Guidance()
    attitude: Attitude = Attitude()
    phases: list[Phase] = Field(default_factory=list)
    assignment: AssignmentSettings = AssignmentSettings()
    fdir: FdirSettings = FdirSettings()
    onboard_fdir: OnboardFdir = OnboardFdir()
    neighbours: Neighbours = Neighbours()
    ground: Ground = Ground()
    sim: SimSettings = SimSettings()
    faults: list[Fault] = Field(default_factory=list)

    @model_validator(mode="after")
    def _consistency(self) -> Scenario:
        if self.duration_s < self.rates.dt_s:
            raise ValueError(f"duration_s = {self.duration_s:g} s is shorter than one tick "
                             f"({self.rates.dt_s:g} s at rates.high_hz)")
        n = self.observers.count
        for f in self.faults:
            if f.spacecraft > n:
                raise ValueError(f"fault on spacecraft {f.spacecraft} but observers.count = {n}")
            if f.start_s >= self.duration_s:
                raise ValueError(f"a {f.kind} fault starts at {f.start_s:g} s, not before the "
                                 f"end of the run (duration_s = {self.duration_s:g})")
        for where, formation in [("observers", self.observers)] + [
                (f"phase {p.name!r}", p) for p in self.phases]:
            for o in formation.overrides:
                if o.spacecraft > n:
                    raise ValueError(f"{where}: override of spacecraft {o.spacecraft} but "
                                     f"observers.count = {n}")
        starts = [p.start_s for p in self.phases]
        if starts != sorted(starts) or len(set(starts)) != len(starts):
            raise ValueError("phases must have strictly increasing start_s")
        ratio = self.rates.high_hz / self.sensors.star_tracker_hz
        if abs(ratio - round(ratio)) > 1e-9 or ratio < 1.0 - 1e-9:
            raise ValueError(f"sensors.star_tracker_hz = {self.sensors.star_tracker_hz} must "
                             f"divide rates.high_hz = {self.rates.high_hz}")
        for c in self.comms.cuts:
            for end in (c.a, c.b):
                if end.startswith("sc") and int(end[2:]) > n:
                    raise ValueError(f"link cut names {end} but observers.count = {n}")
        return self

    @property
    def n_ticks(self) -> int:
        """Number of high-rate ticks in the run (t = 0 .. duration_s)."""
        return int(math.floor(self.duration_s * self.rates.high_hz + 1e-9)) + 1

    def with_overrides(self, seed: int | None = None, duration_s: float | None = None) -> Scenario:
        """A copy with the command-line overrides applied, validated as a file is (a
        ScenarioError naming the key, e.g. ``duration_s``)."""
        data = overridden(self.model_dump(), seed, duration_s)
        return validated(data, "the command line" + _overrides_text(seed, duration_s))


class ScenarioError(ValueError):
    """A scenario file that cannot be read or does not validate; the message names the field,
    one line per error."""


def load_scenario(path: str | Path, seed: int | None = None,
                  duration_s: float | None = None) -> Scenario:
    """Read and validate a scenario TOML file (or, with a ``.json`` suffix, a resolved scenario
    as written by campaigns), with the command line's ``seed`` and ``duration_s`` (s) in place
    of the file's where given: checked once, as the run will fly (a fault is checked against
    the run's duration, not the file's); raise ScenarioError with a readable message."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as e:
        raise ScenarioError(f"cannot read scenario {p}: {e.strerror}") from e
    except UnicodeDecodeError as e:
        raise ScenarioError(f"{p}: not UTF-8 text (byte {e.start}: {e.reason}); a scenario is "
                            "a TOML file") from None
    if p.suffix == ".json":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as e:
            raise ScenarioError(f"{p}: not valid JSON: {e}") from None
    else:
        data = _toml(text, str(p))
    return validated(overridden(data, seed, duration_s),
                     str(p) + _overrides_text(seed, duration_s))


def overridden(data: dict[str, Any], seed: int | None, duration_s: float | None
               ) -> dict[str, Any]:
    """A scenario table with the command line's ``seed`` and ``duration_s`` (s) where given."""
    given = {k: v for k, v in (("seed", seed), ("duration_s", duration_s)) if v is not None}
    return {**data, **given} if isinstance(data, dict) else data


def _overrides_text(seed: int | None, duration_s: float | None) -> str:
    """`` with seed = 3, duration_s = 1400`` for the overrides given (nothing for none)."""
    given = [f"{k} = {v:g}" for k, v in (("seed", seed), ("duration_s", duration_s))
             if v is not None]
    return f" with {', '.join(given)}" if given else ""


def parse_scenario(text: str, source: str = "<string>") -> Scenario:
    """Validate scenario TOML text (see load_scenario)."""
    return validated(_toml(text, source), source)


def _toml(text: str, source: str) -> dict[str, Any]:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{source}: not valid TOML: {e}") from e


def validated(data: dict[str, Any], source: str) -> Scenario:
    """``data`` as a Scenario; ScenarioError naming each invalid key and its value, one line
    each, from ``source`` (``interfaces.contracts.errors``)."""
    try:
        return Scenario.model_validate(data)
    except ValidationError as e:
        raise ScenarioError(describe(e, source, Scenario, data)) from None
