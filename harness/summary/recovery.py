"""summary.json's ``recovery`` section: the final H of a run with and without the ground's
fault recovery (``--compare-recovery``), from outside the archive."""

from __future__ import annotations

from pydantic import (
    Field,
)

from harness.summary.coverage import AssignmentRecord
from harness.summary.records import SummaryRecord


class RecoveryComparison(SummaryRecord):
    """``recovery``: the run against its counterfactual with recovery flipped
    (``--compare-recovery``)."""

    enabled: bool = Field(description="recovery in this run")
    actions: list[AssignmentRecord] = Field(description="the recovery replans of the run "
                                                        "that had recovery on")
    H_final_with_recovery: float | None
    H_final_without_recovery: float | None
    H_final_ratio: float | None = Field(description="with / without")
    counterfactual: str = Field(description="its summary, relative to this one's directory")
    counterfactual_status: str | None


