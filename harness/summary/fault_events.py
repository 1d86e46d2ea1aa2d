"""summary.json's ``fault_events`` section: every switch of an injected fault, as the sim
published it (its truth)."""

from __future__ import annotations

from pydantic import Field

from harness.summary.records import SummaryRecord


class FaultEventRecord(SummaryRecord):
    """The truth of an injected fault switching (a ``FaultEvent`` less its bus header)."""

    t_sim: float = Field(description="sim s")
    spacecraft: int = Field(ge=0, description="0: every observer (common mode)")
    kind: str
    active: bool
    magnitude: float | None = Field(description="as in the scenario (its unit per kind)")
    start_s: float = Field(description="sim s")
    end_s: float | None = Field(description="sim s (null: to the end)")
    detail: dict[str, list[float] | float] = Field(
        description="the realised parameters (faults/hardware.py), SI units")
