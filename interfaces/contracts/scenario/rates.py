"""The rate groups the executives run (ω_high, ω_mid, ω_low) and the FDI period."""

from __future__ import annotations

from pydantic import Field, model_validator

from interfaces.contracts.scenario.base import Section


class Rates(Section):
    """Rate groups ω_high / ω_mid / ω_low (Hz) and the FDI period (s), a whole number of ω_mid
    periods (``interfaces.contracts.fdi_schedule``)."""

    high_hz: float = Field(default=10.0, gt=0.0, le=1000.0)
    mid_hz: float = Field(default=1.0, ge=0.01)
    low_hz: float = Field(default=0.1, ge=0.001, description="at least once in 1,000 s")
    fdi_period_s: float = Field(default=30.0, gt=0.0, le=3600.0)

    @model_validator(mode="after")
    def _integer_ratios(self) -> Rates:
        for name, hz in (("mid_hz", self.mid_hz), ("low_hz", self.low_hz)):
            ratio = self.high_hz / hz
            if hz > self.high_hz or abs(ratio - round(ratio)) > 1e-9:
                raise ValueError(f"rates.{name} = {hz} must divide rates.high_hz = {self.high_hz}")
        if self.low_hz > self.mid_hz:
            raise ValueError("rates.low_hz must not exceed rates.mid_hz")
        ratio = self.mid_hz / self.low_hz
        if abs(ratio - round(ratio)) > 1e-9:
            raise ValueError(f"rates.low_hz = {self.low_hz} must divide "
                             f"rates.mid_hz = {self.mid_hz}")
        mids = self.fdi_period_s * self.mid_hz
        if round(mids) < 1 or abs(mids - round(mids)) > 1e-9:
            raise ValueError(
                f"rates.fdi_period_s = {self.fdi_period_s} s must be a whole number of ω_mid "
                f"periods ({1.0 / self.mid_hz:g} s at rates.mid_hz = {self.mid_hz}): the "
                "observers report H_i and the ground judges at ω_mid steps, so every FDI window "
                "must end on one")
        return self

    @property
    def dt_s(self) -> float:
        """High-rate tick period, s."""
        return 1.0 / self.high_hz

    def ticks_per(self, group: str) -> int:
        """Ticks between two runs of rate group ``group`` ("high", "mid" or "low")."""
        hz = {"high": self.high_hz, "mid": self.mid_hz, "low": self.low_hz}[group]
        return int(round(self.high_hz / hz))
