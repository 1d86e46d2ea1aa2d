"""The ground planner's settings: the information-driven orbit assignment
(``ground/planning/``)."""

from __future__ import annotations

from pydantic import Field, model_validator

from interfaces.contracts.scenario.base import Section


class AssignmentSettings(Section):
    """The central agent's information-driven orbit assignment
    (``ground/planning/orbit_assignment.py``, ``ground/planning/mission_plan.py``), for phases
    with ``assign = "information"``.

    Candidates: every combination of ``rho_x_m`` × ``rho_z_m`` × ``phases`` in-plane phases
    (evenly spread) × ``cross_phase_offsets_deg``; those passing closer than the guidance
    keep-out plus ``keep_out_margin_m`` to the target centre are excluded.  A set is chosen
    greedily by the precision it is expected to add over ``window_s`` after arrival (``samples``
    images, camera on the target centre), with chosen PROs at least ``min_separation_m`` apart.
    Reassignment: every ``check_period_s`` after arrival the ground measures the decrease of H
    of its fused view; when the last window's decrease falls below ``saturation_fraction`` of
    the first, a new set is chosen (leaving one uplink lead later, ``transfer_s`` to arrive).
    The new set is flown only if its expected gain beats the current set's by
    ``min_improvement``; otherwise the current set is kept and measured afresh."""

    rho_x_m: list[float] = Field(default=[10.0, 15.0, 20.0], min_length=1)
    rho_z_m: list[float] = Field(default=[10.0, 20.0, 30.0], min_length=1)
    phases: int = Field(default=6, ge=1, le=72)
    cross_phase_offsets_deg: list[float] = Field(default=[0.0, 90.0], min_length=1)
    window_s: float = Field(default=1200.0, gt=0.0, description="planning window, s")
    samples: int = Field(default=24, ge=1, le=1000, description="images per planning window")
    poi_stride: int = Field(
        default=4, ge=1,
        description="the planner evaluates every k-th POI (φ scaled by k): a uniform subsample "
                    "of the Fibonacci sphere, k times cheaper, for ranking orbits")
    min_separation_m: float = Field(default=5.0, ge=0.0)
    keep_out_margin_m: float = Field(default=2.0, ge=0.0)
    check_period_s: float = Field(default=300.0, gt=0.0)
    saturation_fraction: float = Field(default=0.5, gt=0.0, lt=1.0)
    min_improvement: float = Field(default=0.1, ge=0.0,
                                   description="relative expected-gain margin to switch sets")
    transfer_s: float = Field(default=600.0, gt=0.0, description="reassignment transfer time, s")

    @model_validator(mode="after")
    def _amplitudes(self) -> AssignmentSettings:
        for name in ("rho_x_m", "rho_z_m"):
            if any(v < 0.0 or v > 1000.0 for v in getattr(self, name)):
                raise ValueError(f"assignment.{name} values must be in [0, 1000] m")
        return self
