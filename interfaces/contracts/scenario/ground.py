"""The ground segment: how the ground hears the constellation (``[ground]``).

``contact = "continuous"`` (the default) is a ground that hears every observer at every instant,
through the target; ``"passes"`` hears only while a station sees the target
(``gnc/passes.py``), with telemetry stored onboard in between and dumped at the next pass.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Literal

from pydantic import Field, field_validator, model_validator

from interfaces.contracts.scenario.base import Section


class Station(Section):
    """A ground station: geodetic latitude and longitude (degrees, WGS-84), altitude above the
    ellipsoid (m), and the elevation mask (degrees above the local horizon) above which it sees
    the target."""

    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$")
    latitude_deg: float = Field(ge=-90.0, le=90.0)
    longitude_deg: float = Field(ge=-180.0, le=360.0)
    altitude_m: float = Field(default=0.0, ge=-500.0, le=9000.0)
    elevation_mask_deg: float = Field(
        default=10.0, ge=0.0, lt=90.0,
        description="a mask below the horizon (< 0) would see through the Earth")


class Ground(Section):
    contact: Literal["continuous", "passes"] = "continuous"
    epoch: datetime = Field(
        default=datetime(2026, 3, 20, 12, 0, 0, tzinfo=UTC),
        description="UTC at t = 0: the Earth's sidereal angle then (where the stations are)")
    stations: list[Station] = Field(default_factory=list)
    downlink_bps: float = Field(
        default=50.0e6, gt=0.0,
        description="each spacecraft's dump rate in a pass, bit/s (an X-band small-spacecraft "
                    "transmitter: docs/architecture.md, \"Data budget\")")
    store_bytes: int = Field(
        default=8 * 2 ** 30, gt=0,
        description="each spacecraft's telemetry store, bytes (a small spacecraft's mass "
                    "memory: docs/architecture.md, \"Data budget\")")

    @field_validator("epoch")
    @classmethod
    def _utc(cls, v: datetime) -> datetime:
        if v.tzinfo is None:
            raise ValueError("epoch needs a time zone (e.g. 2026-03-20T12:00:00Z)")
        return v.astimezone(UTC)

    @model_validator(mode="after")
    def _stations(self) -> Ground:
        names = [s.name for s in self.stations]
        if len(set(names)) != len(names):
            raise ValueError(f"station names must be unique, got {names}")
        if self.contact == "passes" and not self.stations:
            raise ValueError('contact = "passes" needs at least one [[ground.stations]]')
        return self
