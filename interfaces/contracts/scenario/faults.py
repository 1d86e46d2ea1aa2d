"""The scenario's ``[[faults]]``: what the fault-injection harness (``faults/``) switches on
and off, and when."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from interfaces.contracts.scenario.base import Section

FaultKind = Literal[
    "thruster_bias",
    "pointing_actuator",
    "camera_degradation",
    "camera_misalignment",
    "nav_sensor_bias",
    "link_loss",
    "packet_loss",
    "faulty_data",
    "camera_calibration",
    "state_disturbance",
]
COMMON_MODE_KINDS = frozenset({"camera_calibration"})
"""Fault kinds that act on every observer at once (``spacecraft = 0``): a camera calibration
error (the true variance coefficient is k / ``magnitude``: every precision scaled by it) that no
single observer explains."""



class Fault(Section):
    spacecraft: int = Field(ge=0, description="the faulty observer; 0 for a common-mode kind")
    kind: FaultKind
    start_s: float = Field(ge=0.0)
    end_s: float | None = None
    magnitude: float | None = None
    velocity_mps: float | None = None
    """``state_disturbance`` only: the velocity part, m/s (the position part is ``magnitude``,
    m)"""
    disturbance: Literal["bias", "noise"] | None = None
    """``state_disturbance`` only: a seeded-direction offset (``bias``, the default) or a
    Gaussian draw per axis (``noise``); faults/hardware.py says how each acts in time"""

    @model_validator(mode="after")
    def _magnitude(self) -> Fault:
        if self.end_s is not None and self.end_s <= self.start_s:
            raise ValueError("fault end_s must be after start_s")
        if (self.spacecraft == 0) != (self.kind in COMMON_MODE_KINDS):
            raise ValueError(f"fault kind {self.kind!r} acts on "
                             + ("every observer: give spacecraft = 0"
                                if self.kind in COMMON_MODE_KINDS else "one observer (>= 1)"))
        if self.kind == "state_disturbance":
            return self._disturbance()
        if self.velocity_mps is not None or self.disturbance is not None:
            raise ValueError(f"fault kind {self.kind!r}: velocity_mps and disturbance are for "
                             "state_disturbance only")
        if self.kind == "link_loss":
            return self
        if self.magnitude is None:
            raise ValueError(f"fault kind {self.kind!r} needs a magnitude")
        if (self.kind in ("camera_degradation", "packet_loss", "camera_calibration")
                and not 0.0 < self.magnitude < 1.0):
            raise ValueError(f"{self.kind} magnitude must be in (0, 1), got {self.magnitude}")
        return self

    def _disturbance(self) -> Fault:
        """A state disturbance (Sec. III.G's actuator fault): position ``magnitude`` (m) and
        ``velocity_mps`` (m/s), neither negative, not both zero."""
        if self.magnitude is None:
            raise ValueError("fault kind 'state_disturbance' needs a magnitude (position "
                             "disturbance, m; 0 for a velocity-only one)")
        dv = self.velocity_mps or 0.0
        if self.magnitude < 0.0 or dv < 0.0 or self.magnitude + dv == 0.0:
            raise ValueError("state_disturbance magnitude (m) and velocity_mps (m/s) must be "
                             f">= 0 and not both 0, got {self.magnitude} and {dv}")
        return self
