"""The scenario's ``[[faults]]``: what the fault-injection harness (``faults/``) switches on
and off, and when."""

from __future__ import annotations

import math
from dataclasses import dataclass
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


@dataclass(frozen=True)
class MagnitudeRange:
    """The physical range of a fault kind's ``magnitude``: (low, high], or (low, high) when
    ``high_open``; its unit, and what it is."""

    low: float
    high: float
    meaning: str
    high_open: bool = False

    def holds(self, value: float) -> bool:
        return math.isfinite(value) and self.low < value and (
            value < self.high if self.high_open else value <= self.high)

    def __str__(self) -> str:
        return f"in ({self.low:g}, {self.high:g}{')' if self.high_open else ']'} ({self.meaning})"


MAGNITUDES: dict[str, MagnitudeRange | None] = {
    "thruster_bias": MagnitudeRange(0.0, 1.0, "a leak, fraction of the maximum thrust"),
    "pointing_actuator": MagnitudeRange(0.0, 45.0, "degrees off the target"),
    "camera_degradation": MagnitudeRange(0.0, 1.0, "β, the share of precision kept", True),
    "camera_misalignment": MagnitudeRange(0.0, 45.0, "degrees of boresight rotation"),
    "nav_sensor_bias": MagnitudeRange(0.0, 100.0, "m of relative-position offset"),
    "link_loss": None,
    "packet_loss": MagnitudeRange(0.0, 1.0, "loss probability on its links", True),
    "faulty_data": MagnitudeRange(0.0, 100.0, "factor on the H_i it reports, not 1"),
    "camera_calibration": MagnitudeRange(0.0, 1.0, "factor on every precision", True),
    "state_disturbance": None,
}
"""Each kind's magnitude (``faults/hardware.py``, ``faults/software.py`` say how each acts);
None: ``link_loss`` takes none, ``state_disturbance`` has its own (position m ≤
``MAX_DISTURBANCE_M``, velocity m/s ≤ ``MAX_DISTURBANCE_MPS``)."""
NO_MAGNITUDE = frozenset({"link_loss"})
"""Fault kinds that take no magnitude."""
MAX_DISTURBANCE_M, MAX_DISTURBANCE_MPS = 1000.0, 10.0



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
        if self.kind in NO_MAGNITUDE:
            if self.magnitude is not None:
                raise ValueError(f"fault kind {self.kind!r} takes no magnitude, got "
                                 f"{self.magnitude}")
            return self
        if self.magnitude is None:
            raise ValueError(f"fault kind {self.kind!r} needs a magnitude")
        bounds = MAGNITUDES[self.kind]
        if bounds is not None and (not bounds.holds(self.magnitude)
                                   or self.kind == "faulty_data" and self.magnitude == 1.0):
            raise ValueError(f"{self.kind} magnitude must be {bounds}, got {self.magnitude}")
        return self

    def _disturbance(self) -> Fault:
        """A state disturbance (Sec. III.G's actuator fault): position ``magnitude`` (m) and
        ``velocity_mps`` (m/s), neither negative, not both zero."""
        if self.magnitude is None:
            raise ValueError("fault kind 'state_disturbance' needs a magnitude (position "
                             "disturbance, m; 0 for a velocity-only one)")
        dv = self.velocity_mps or 0.0
        if not (0.0 <= self.magnitude <= MAX_DISTURBANCE_M and 0.0 <= dv <= MAX_DISTURBANCE_MPS
                and self.magnitude + dv > 0.0):
            raise ValueError(f"state_disturbance magnitude (m) and velocity_mps (m/s) must be in "
                             f"[0, {MAX_DISTURBANCE_M:g}] and [0, {MAX_DISTURBANCE_MPS:g}], not "
                             f"both 0, got {self.magnitude} and {dv}")
        return self
