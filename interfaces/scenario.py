"""Scenario files (TOML) as pydantic models: the contract of DESIGN.md ("Scenario TOML").

Every section has defaults, so a scenario states only what differs.  Unknown keys are errors
(a typo must not silently fall back to a default); values are checked for range and
consistency, and errors name the file and the offending field.
"""

from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

FaultKind = Literal[
    "thruster_bias",
    "pointing_actuator",
    "camera_degradation",
    "camera_misalignment",
    "nav_sensor_bias",
    "link_loss",
    "packet_loss",
    "faulty_data",
]


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class Orbit(_Section):
    """Target (chief) orbit: circular at ``altitude_km``."""

    altitude_km: float = Field(default=500.0, gt=100.0, lt=40000.0)
    inclination_deg: float = Field(default=51.6, ge=0.0, le=180.0)
    j2: bool = Field(default=False, description="include J2 in the truth dynamics")


class Target(_Section):
    shape: Literal["sphere"] = "sphere"
    radius_m: float = Field(default=5.0, gt=0.0)
    pois: int = Field(default=5000, ge=1)


class Rates(_Section):
    """Rate groups ω_high / ω_mid / ω_low (Hz) and the FDI period (s)."""

    high_hz: float = Field(default=10.0, gt=0.0)
    mid_hz: float = Field(default=1.0, gt=0.0)
    low_hz: float = Field(default=0.1, gt=0.0)
    fdi_period_s: float = Field(default=100.0, gt=0.0)

    @model_validator(mode="after")
    def _integer_ratios(self) -> Rates:
        for name, hz in (("mid_hz", self.mid_hz), ("low_hz", self.low_hz)):
            ratio = self.high_hz / hz
            if hz > self.high_hz or abs(ratio - round(ratio)) > 1e-9:
                raise ValueError(f"rates.{name} = {hz} must divide rates.high_hz = {self.high_hz}")
        if self.low_hz > self.mid_hz:
            raise ValueError("rates.low_hz must not exceed rates.mid_hz")
        return self

    @property
    def dt_s(self) -> float:
        """High-rate tick period, s."""
        return 1.0 / self.high_hz

    def ticks_per(self, group: str) -> int:
        """Ticks between two runs of rate group ``group`` ("high", "mid" or "low")."""
        hz = {"high": self.high_hz, "mid": self.mid_hz, "low": self.low_hz}[group]
        return int(round(self.high_hz / hz))


class Burst(_Section):
    """Gilbert-Elliott burst loss: the average loss rate is ``comms.packet_loss``; losses come in
    bursts of geometric length with this mean (packets)."""

    mean_length_packets: float = Field(ge=1.0)


class LinkCut(_Section):
    """Cut the link between nodes ``a`` and ``b`` ("sc<N>", "ground" or "*" for any) over
    [start_s, end_s)."""

    a: str
    b: str = "*"
    start_s: float = Field(default=0.0, ge=0.0)
    end_s: float = math.inf

    @model_validator(mode="after")
    def _nodes(self) -> LinkCut:
        for n in (self.a, self.b):
            if not re.fullmatch(r"sc\d+|ground|\*", n):
                raise ValueError(f"link cut end {n!r}: expected 'sc<N>', 'ground' or '*'")
        if self.end_s <= self.start_s:
            raise ValueError("link cut end_s must be after start_s")
        return self

    model_config = ConfigDict(extra="forbid", allow_inf_nan=True, frozen=True)


class Comms(_Section):
    """Inter-spacecraft and spacecraft-ground links.  The ground is reached through the target
    spacecraft (the mothership relay at the LVLH origin), so a spacecraft is in ground contact when
    it is within ``range_m`` of the target."""

    range_m: float = Field(default=200.0, gt=0.0)
    packet_loss: float = Field(default=0.0, ge=0.0, lt=1.0)
    burst: Burst | None = None
    delay_s: float = Field(default=0.0, ge=0.0)
    cuts: list[LinkCut] = Field(default_factory=list)


class ObserverOverride(_Section):
    spacecraft: int = Field(ge=1)
    rho_x_m: float | None = None
    alpha_x_deg: float | None = None
    rho_y_m: float | None = None
    rho_z_m: float | None = None
    alpha_z_deg: float | None = None


class Observers(_Section):
    """Observers start on passive relative orbits (HCW form, DESIGN/REFERENCE):
    x = ρx sin(nt+αx), y = ρy + 2ρx cos(nt+αx), z = ρz sin(nt+αz).  By default spacecraft i of N
    has αx = αz = 360°·(i-1)/N; ``overrides`` set any parameter of one spacecraft."""

    count: int = Field(default=5, ge=1, le=64)
    rho_x_m: float = Field(default=20.0, ge=0.0)
    rho_y_m: float = 0.0
    rho_z_m: float = Field(default=20.0, ge=0.0)
    energy_match: bool = Field(default=True, description="match the target's semi-major axis")
    mass_kg: float = Field(default=10.0, gt=0.0)
    overrides: list[ObserverOverride] = Field(default_factory=list)

    def pro(self, spacecraft: int) -> tuple[float, float, float, float, float]:
        """(ρx m, αx rad, ρy m, ρz m, αz rad) of ``spacecraft`` (1-based)."""
        phase = 360.0 * (spacecraft - 1) / self.count
        p = {"rho_x_m": self.rho_x_m, "alpha_x_deg": phase, "rho_y_m": self.rho_y_m,
             "rho_z_m": self.rho_z_m, "alpha_z_deg": phase}
        for o in self.overrides:
            if o.spacecraft == spacecraft:
                p.update({k: v for k, v in o.model_dump().items() if v is not None and k in p})
        return (p["rho_x_m"], math.radians(p["alpha_x_deg"]), p["rho_y_m"], p["rho_z_m"],
                math.radians(p["alpha_z_deg"]))


class Sensors(_Section):
    relnav_sigma_r_m: float = Field(default=0.1, gt=0.0, description="1σ position noise, m")
    relnav_sigma_v_mps: float = Field(default=0.002, gt=0.0, description="1σ velocity noise, m/s")


class Nav(_Section):
    q_accel_m2_s3: float = Field(
        default=1e-12, gt=0.0, description="spectral density of unmodelled acceleration, m²/s³"
    )


class SimSettings(_Section):
    lockstep_timeout_s: float = Field(default=5.0, gt=0.0, description="per-tick answer timeout")
    startup_timeout_s: float = Field(default=60.0, gt=0.0)
    substeps: int = Field(default=1, ge=1, description="RK4 steps per tick")
    cycle_budget_scale: float = Field(
        default=1.0, gt=0.0,
        description="a rate group overruns when its wall time exceeds its period times this",
    )


class Fault(_Section):
    spacecraft: int = Field(ge=1)
    kind: FaultKind
    start_s: float = Field(ge=0.0)
    end_s: float | None = None
    magnitude: float | None = None

    @model_validator(mode="after")
    def _magnitude(self) -> Fault:
        if self.end_s is not None and self.end_s <= self.start_s:
            raise ValueError("fault end_s must be after start_s")
        if self.kind == "link_loss":
            return self
        if self.magnitude is None:
            raise ValueError(f"fault kind {self.kind!r} needs a magnitude")
        if self.kind in ("camera_degradation", "packet_loss") and not 0.0 < self.magnitude < 1.0:
            raise ValueError(f"{self.kind} magnitude must be in (0, 1), got {self.magnitude}")
        return self


class Scenario(_Section):
    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$")
    seed: int = Field(default=0, ge=0)
    duration_s: float = Field(gt=0.0)
    orbit: Orbit = Orbit()
    target: Target = Target()
    rates: Rates = Rates()
    comms: Comms = Comms()
    observers: Observers = Observers()
    sensors: Sensors = Sensors()
    nav: Nav = Nav()
    sim: SimSettings = SimSettings()
    faults: list[Fault] = Field(default_factory=list)

    @model_validator(mode="after")
    def _consistency(self) -> Scenario:
        n = self.observers.count
        for f in self.faults:
            if f.spacecraft > n:
                raise ValueError(f"fault on spacecraft {f.spacecraft} but observers.count = {n}")
        for o in self.observers.overrides:
            if o.spacecraft > n:
                raise ValueError(f"override of spacecraft {o.spacecraft} but observers.count = {n}")
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
        """A copy with the command-line overrides applied (and validated)."""
        data = self.model_dump()
        if seed is not None:
            data["seed"] = seed
        if duration_s is not None:
            data["duration_s"] = duration_s
        return Scenario.model_validate(data)


class ScenarioError(ValueError):
    """A scenario file that cannot be read or does not validate; the message names the field."""


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file; raise ScenarioError with a readable message."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as e:
        raise ScenarioError(f"cannot read scenario {p}: {e.strerror}") from e
    return parse_scenario(text, source=str(p))


def parse_scenario(text: str, source: str = "<string>") -> Scenario:
    """Validate scenario TOML text (see load_scenario)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{source}: not valid TOML: {e}") from e
    try:
        return Scenario.model_validate(data)
    except ValidationError as e:
        lines = [f"{source}: invalid scenario:"]
        for err in e.errors():
            where = ".".join(str(x) for x in err["loc"]) or "(top level)"
            lines.append(f"  {where}: {err['msg']}")
        raise ScenarioError("\n".join(lines)) from None
