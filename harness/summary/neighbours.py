"""``neighbours``: what the neighbours' FDIR aboard did (fsw/apps/neighbours.py), present when the
scenario turns it on (``[neighbours] enabled``): its declarations with the ground's rulings,
its scores as a detector of its own, its windows, and where it and the ground disagreed."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from harness.summary.fdir import Scores
from harness.summary.records import SummaryRecord


class NeighbourWindows(SummaryRecord):
    """The neighbours' windows: a subject's FDI window that at least one neighbour decided
    (a neighbour-window), and each judge's decided verdict on one (a judge-window)."""

    neighbour_windows: int = Field(ge=0, description="subject windows decided, any fault")
    judge_windows: int = Field(ge=0, description="judges' decided verdicts, any fault")
    nominal_judge_windows: int = Field(ge=0, description="those on a subject with no fault")
    nominal_exceeded: int = Field(ge=0, description="of those, the verdicts that failed")


class Disagreements(SummaryRecord):
    """Where the ground and the neighbours disagreed: a declaration the ground overruled, and a
    fault the ground declared on a spacecraft the neighbours had not declared by then."""

    overruled: int = Field(ge=0)
    upheld: int = Field(ge=0)
    unruled: int = Field(ge=0, description="declarations the ground had not ruled on by the end")
    ground_only: int = Field(ge=0, description="ground declarations (first of each spacecraft's "
                                              "episode) the neighbours had not made")


class NeighboursSummary(SummaryRecord):
    """The neighbours' FDIR over the run.  Its declarations are also in ``detections``
    (``declared_by = "neighbours"``)."""

    agree: int = Field(description="the agreement rule's quorum ([neighbours] agree)")
    scores: Scores = Field(description="its declarations scored as the ground's are, per "
                                       "neighbour-window")
    windows: NeighbourWindows
    disagreements: Disagreements
    rulings: dict[str, Literal["upheld", "overruled"]] = Field(
        default_factory=dict, description="by 'subject@window end s'")
