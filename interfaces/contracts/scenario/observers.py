"""The observers' formation: how many, their PROs and overrides, the deployment, and the
mission's phases (formations the ground assigns in turn)."""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, model_validator

from interfaces.contracts.scenario.base import Section

MAX_PRO_M = 10_000.0
"""The largest PRO size, m: an inspection flies tens of metres, and the relative navigation
measures within 100 km (ρy + 2ρx at most 30 km)."""
Size = Annotated[float, Field(ge=0.0, le=MAX_PRO_M)]
Offset = Annotated[float, Field(ge=-MAX_PRO_M, le=MAX_PRO_M)]
Angle = Annotated[float, Field(ge=-360.0, le=360.0)]
"""A PRO phase, deg."""


class ObserverOverride(Section):
    spacecraft: int = Field(ge=1)
    rho_x_m: Size | None = None
    alpha_x_deg: Angle | None = None
    rho_y_m: Offset | None = None
    rho_z_m: Size | None = None
    alpha_z_deg: Angle | None = None


class _ProFormation(Section):
    """A set of passive relative orbits, one per observer (HCW form):
    x = ρx sin(nt+αx), y = ρy + 2ρx cos(nt+αx), z = ρz sin(nt+αz), t from the mission start.
    By default spacecraft i of N has αx = αz = phase0_deg + 360°·(i-1)/N; ``overrides`` set any
    parameter of one spacecraft."""

    rho_x_m: Size = 20.0
    rho_y_m: Offset = 0.0
    rho_z_m: Size = 20.0
    phase0_deg: Angle = 0.0
    overrides: list[ObserverOverride] = Field(default_factory=list)

    def pro_of(self, spacecraft: int, count: int) -> tuple[float, float, float, float, float]:
        """(ρx m, αx rad, ρy m, ρz m, αz rad) of ``spacecraft`` (1-based) of ``count``."""
        phase = self.phase0_deg + 360.0 * (spacecraft - 1) / count
        p = {"rho_x_m": self.rho_x_m, "alpha_x_deg": phase, "rho_y_m": self.rho_y_m,
             "rho_z_m": self.rho_z_m, "alpha_z_deg": phase}
        for o in self.overrides:
            if o.spacecraft == spacecraft:
                p.update({k: v for k, v in o.model_dump().items() if v is not None and k in p})
        return (p["rho_x_m"], math.radians(p["alpha_x_deg"]), p["rho_y_m"], p["rho_z_m"],
                math.radians(p["alpha_z_deg"]))


class Observers(_ProFormation):
    """The observers and their initial conditions.  ``start = "pro"``: they start on the PROs of
    this section; ``start = "deploy"``: they are released from the target (Fig. 7, phase 1) at
    ``deploy_radius_m`` from its centre with ``deploy_speed_mps`` outward, directions fanned
    evenly in the along-track/cross-track plane, and drift until the first phase.  The initial
    attitude is drawn from the seed (``initial_attitude = "random"``) or aligned with LVLH, with
    a 1σ tumble rate per axis."""

    count: int = Field(default=5, ge=1, le=64)
    energy_match: bool = Field(default=True, description="match the target's semi-major axis")
    mass_kg: float = Field(default=10.0, gt=0.0)
    inertia_kg_m2: tuple[float, float, float] = Field(
        default=(0.10, 0.12, 0.08), description="principal moments of inertia, kg·m²")
    start: Literal["pro", "deploy"] = "pro"
    deploy_radius_m: float = Field(default=5.0, gt=0.0)
    deploy_speed_mps: float = Field(default=0.05, ge=0.0)
    initial_attitude: Literal["random", "lvlh"] = "random"
    tumble_rate_dps: float = Field(
        default=0.2, ge=0.0, le=90.0,
        description="1σ initial rate per axis, deg/s (at most 90: a draw stays within the truth "
                    "state's 10 rad/s bound to 6σ)")

    @model_validator(mode="after")
    def _inertia(self) -> Observers:
        a, b, c = self.inertia_kg_m2
        if min(a, b, c) <= 0 or a + b < c or a + c < b or b + c < a:
            raise ValueError("observers.inertia_kg_m2 must be positive and satisfy the triangle "
                             "inequality of principal moments")
        return self

    def pro(self, spacecraft: int) -> tuple[float, float, float, float, float]:
        """(ρx m, αx rad, ρy m, ρz m, αz rad) of ``spacecraft`` (1-based)."""
        return self.pro_of(spacecraft, self.count)


class Phase(_ProFormation):
    """A phase of the mission plan (Fig. 7): at ``start_s`` every observer leaves its orbit for
    the PRO of this phase, arriving ``transfer_s`` later (fuel-optimal SCP transfer, then held).

    ``assign = "scenario"``: the PROs are the ones given here.  ``assign = "information"``: the
    ground chooses them from the candidate library of ``[assignment]`` by expected information
    gain when the phase is uplinked, and reassigns whenever the gain of the set saturates, until
    the next phase (the PRO fields of the phase are then unused)."""

    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$")
    start_s: float = Field(ge=0.0)
    transfer_s: float = Field(default=900.0, gt=0.0)
    assign: Literal["scenario", "information"] = "scenario"
