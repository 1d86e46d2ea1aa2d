"""summary.json's sections on how the run went, from its archive: navigation, guidance and
attitude, inspection coverage, links, executives, the sim, the injected faults' truth; and
the sections added from outside the archive (the router's access audit, the recovery
comparison)."""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

from pydantic import BeforeValidator, Field, SerializerFunctionWrapHandler, WrapSerializer

from harness.summary.records import Figure, SummaryRecord
from interfaces.contracts.messages import SimStatus

BUS_HEADER = frozenset({"sender", "seq", "t_wall"})
"""A message's fields the bus stamps: the summary's copies of messages leave them out."""


class SegmentRecord(SummaryRecord):
    """One file of a run's archive (``ground/archive/segments.py``)."""

    file: str = Field(description="its name, beside summary.json")
    truncated: bool = Field(description="it ends in a damaged record or before its footer "
                                        "(its recorder died; what precedes is kept)")


class LostMessages(SummaryRecord):
    """Messages sent and never archived, from the gaps in each key's sequence numbers
    (``harness/archive/sequences.py``)."""

    total: int = Field(ge=0)
    by_topic: dict[str, int] = Field(
        description="by catalogue topic (app/name, every publisher's keys together; a key "
                    "outside the catalogue by itself), in name order, topics with none left out")


class ArchiveInfo(SummaryRecord):
    """``archive``: the state of the run's archive as read back.  ``segments`` and ``lost``
    are given together, only when the archive has several segments (the recorder was
    restarted) or lost messages: absent, the run is one file, run.mcap, and nothing sent is
    missing from it."""

    truncated: bool = Field(description="a file of it ends in a damaged record (what precedes "
                                        "is kept)")
    segments: list[SegmentRecord] | None = Field(
        default=None, description="each file, in order (absent: run.mcap alone)")
    lost: LostMessages | None = Field(default=None, description="(absent: none lost)")


class MessageCounts(SummaryRecord):
    """``messages``: the records archived."""

    total: int = Field(ge=0)
    by_type: dict[str, int] = Field(description="by message type, in name order")


class NavStats(SummaryRecord):
    """One observer's navigation errors after the filter's first seconds
    (``harness.summary.build.NAV_SETTLE_S``)."""

    samples: int = Field(ge=0, description="estimates compared with the truth")
    pos_rms_m: float
    pos_max_m: float
    vel_rms_mps: float
    nees_mean: float = Field(description="mean normalised estimation error squared (6 dof)")
    nees_in_95_bounds: float = Field(description="share of NEES within the χ²(6) 95% bounds")
    nis_mean: Figure = Field(description="mean normalised innovation squared (null: none)")


def _none_if_empty(v: Any) -> Any:
    return None if v == {} else v


def _empty_if_none(v: NavStats | None, handler: SerializerFunctionWrapHandler) -> Any:
    return {} if v is None else handler(v)


NavEntry = Annotated[NavStats | None, BeforeValidator(_none_if_empty),
                     WrapSerializer(_empty_if_none)]
"""An observer's nav statistics; None (``{}`` on disk) when it has no estimate after the
settling time."""


class GncStats(SummaryRecord):
    """One observer's guidance and attitude figures (``harness.summary.control_eval``)."""

    dv_delivered_l1_mps: float = Field(description="Δv delivered, L1 norm, m/s")
    dv_commanded_l1_mps: float = Field(description="Δv commanded, L1 norm, m/s")
    dv_planned_l1_mps: float = Field(description="Δv of the planned transfers, L1 norm, m/s")
    transfers: int = Field(ge=0, description="transfers planned and solved")
    min_range_m: Figure = Field(description="closest approach to the target, m")
    hold_samples: int = Field(ge=0, description="samples of PRO station-keeping")
    hold_error_rms_m: Figure = Field(description="PRO hold error, RMS, m")
    hold_error_max_m: Figure = Field(description="PRO hold error, max, m")
    pointing_samples_track: int = Field(ge=0, description="attitude samples in track mode")
    pointing_error_mean_deg: Figure = Field(description="in track mode, deg")
    pointing_error_p95_deg: Figure = Field(description="in track mode, deg")
    pointing_error_max_deg: Figure = Field(description="in track mode, deg")
    fraction_tracking: float = Field(description="share of attitude samples in track mode")
    knowledge_error_rms_arcsec: Figure = Field(description="attitude knowledge error, arcsec")


class AssignmentRecord(SummaryRecord):
    """An orbit assignment decision of the ground (an ``AssignmentDecision`` less its bus
    header)."""

    t_sim: float = Field(description="when decided, sim s")
    phase: str
    reason: Literal["phase", "saturated", "recovery"]
    library_indices: list[int] = Field(
        description="candidate PRO of observer 1, 2, ... (-1: kept its PRO)")
    expected_gain: float = Field(description="expected information gain (H, dimensionless)")
    upper_bound: float = Field(description="its online upper bound, same unit")
    ratio_bound: float = Field(description="expected_gain / upper_bound")
    current_gain: float | None = Field(description="expected gain of the current PROs")
    measured_gains: list[float] = Field(description="H decrease per check window")
    switched: bool = Field(description="whether it was flown")


class CoverageSummary(SummaryRecord):
    """``coverage``: the inspection's information cost H (dimensionless, Eq. 8)."""

    H_initial: float = Field(description="H before any image")
    H_final: float = Field(description="H at the end")
    fraction_observed: float = Field(description="share of the POIs observed at least once")
    H_i_final: dict[str, float] = Field(description="each observer's last reported H_i")
    H_reduction_fraction: float = Field(description="1 - H_final / H_initial")
    assignment_decisions: list[AssignmentRecord]


class ExecRecord(SummaryRecord):
    """One node's executive counters, cumulative over the run (``ExecStats``)."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("refused",)

    cycle_slips: dict[str, int] = Field(description="runs over budget, by rate group")
    max_exec_ms: dict[str, float] = Field(description="longest run, ms (wall), by rate group")
    app_errors: int = Field(ge=0)
    invalid_dropped: int = Field(ge=0, description="invalid messages dropped")
    refused: int = Field(default=0, ge=0, description="messages refused at admission")
    barrier_timeouts: int = Field(ge=0)


class PaceRecord(SummaryRecord):
    """``sim.pace``: how a ``--realtime`` run was paced (``sim/pacing.py``); the factor it
    achieved is the summary's ``real_time_factor``."""

    ceiling: float = Field(gt=0.0, description="--realtime SPEED, × real time")
    hard_deadline: bool = Field(description="answers waited for only until the next tick")
    late_ticks: dict[str, int] = Field(
        default_factory=dict, description="per node, the ticks its answer came too late for")


class SimRecord(SummaryRecord):
    """``sim``: the sim's last status."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("participants",)

    rejected_commands: int | None = Field(
        description="actuator commands refused (null: no status received)")
    participants: dict[str, list[SimStatus.Event]] = Field(
        default_factory=dict, description="nodes lost from the lockstep and rejoined, by node")
    pace: PaceRecord | None = Field(
        default=None, description="a --realtime run's pacing (absent: lockstep alone)")


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


class AccessAudit(SummaryRecord):
    """``access``: the router's refusals when the run was audited (logs/access.json)."""

    refused: dict[str, int] = Field(description="refusals by kind")
    total: int = Field(ge=0)


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
