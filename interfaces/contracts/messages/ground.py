"""Messages the ground publishes: orbit assignments and the planner's decisions, FDIR windows
and fault reports, baseline verdicts, telemetry status."""

from __future__ import annotations

from typing import Annotated, Literal, get_args

from pydantic import BaseModel, ConfigDict, Field, model_validator

from interfaces.contracts.messages.base import Message, Time, Unjudged

MAX_PRO_SIZE_M = 1.0e5
"""Largest PRO amplitude or offset a command may carry, m (far beyond the HCW model's range)."""


MAX_TRANSFER_S = 86400.0
"""Longest transfer a command may ask for, s."""


class ProElements(BaseModel):
    """A passive relative orbit: x = ρx sin(nt+αx), y = ρy + 2ρx cos(nt+αx), z = ρz sin(nt+αz),
    t from the mission start (s); m and rad."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    rho_x_m: float = Field(ge=0.0, le=MAX_PRO_SIZE_M)
    alpha_x_rad: float = Field(ge=-100.0, le=100.0)
    rho_y_m: float = Field(ge=-MAX_PRO_SIZE_M, le=MAX_PRO_SIZE_M)
    rho_z_m: float = Field(ge=0.0, le=MAX_PRO_SIZE_M)
    alpha_z_rad: float = Field(ge=-100.0, le=100.0)


class ProAssignment(BaseModel):
    """Be on ``pro`` from ``t_arrive_s``, leaving the current orbit at ``t_depart_s`` (s, mission
    time).  A spacecraft acts on a new ``assignment_id`` once (commands are idempotent)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    spacecraft: int = Field(ge=1)
    assignment_id: int = Field(ge=1)
    phase: str = Field(max_length=64)
    pro: ProElements
    t_depart_s: Time
    t_arrive_s: Time

    @model_validator(mode="after")
    def _times(self) -> ProAssignment:
        if not 0.0 <= self.t_arrive_s - self.t_depart_s <= MAX_TRANSFER_S:
            raise ValueError(f"t_arrive_s must be within {MAX_TRANSFER_S:.0f} s after t_depart_s")
        return self


class ProAssignments(Message):
    """Ground command: the current PRO assignment of every observer, repeated by the ground until
    superseded (each spacecraft reads its own entry; the link decides per receiver)."""

    assignments: list[ProAssignment]


WindowTest = Literal["information", "plan", "pointing", "dv_rate", "nis"]
"""The main detector's tests of an observer's window: the information test (Eq. 9 against the
threshold), the guidance and attitude consistency tests and the nav's NIS test
(ground/fdir/consistency.py)."""


WINDOW_TESTS: tuple[str, ...] = get_args(WindowTest)



class FdirWindow(Message):
    """The FDIR's verdict on one observer over one FDI window [t_start_s, t_end_s): the
    information gained by the images that reached the ground (ΔH_i, ψ held at the window start)
    against the nominal twin's prediction for the same images, the metric H_m,i (Eq. 9), the
    adaptive threshold τ_i (Eq. 11-12), the direction (Table 3) and whether it was exceeded
    (None: no decision — no images, no plan, or a degenerate prediction), with the
    identification evidence (ground/fdir/identify.py ``Evidence``) and the observations lost
    (sequence gaps)."""

    spacecraft: int = Field(ge=1)
    t_start_s: Time
    t_end_s: Time
    images: int = Field(ge=0)
    lost: int = Field(default=0, ge=0, description="observations missing by sequence number")
    dh: float | None = None
    dh_pred: float | None = None
    metric: float | None = None
    threshold: float | None = None
    direction: Literal["improved", "degraded"] | None = None
    exceeded: bool | None = None
    evidence: dict[str, float] = Field(default_factory=dict, max_length=32)
    threshold_model: float | None = Field(
        default=None, description="τ from the hardware's nominal ratio distribution "
                                  "(gnc/hardware_threshold.py)")
    threshold_sampled: float | None = Field(
        default=None, description="τ of Eq. 11-12 (ε-sampled pointings), before the floor")
    threshold_by: Literal["model", "sampled", "floor"] | None = Field(
        default=None, description="what set the threshold in force: the selected threshold, "
                                  "or the floor guard above it")
    ratio_mean: float | None = Field(default=None, description="nominal mean of ΔH_i/ΔH_i^pred")
    ratio_std: float | None = Field(default=None, description="nominal 1σ of ΔH_i/ΔH_i^pred")
    nis_sum: float | None = Field(
        default=None, ge=0.0,
        description="Σ NIS of the observer's nav updates in the window (fdir.fuse_nis)")
    nis_limit: float | None = Field(
        default=None, description="its χ²(6N) quantile at the window's false-alarm probability")
    nis_updates: int | None = Field(default=None, ge=0, description="N, the updates summed")
    failed: list[WindowTest] = Field(
        default_factory=list, max_length=len(WINDOW_TESTS),
        description="the detector's tests this window failed (ground/fdir/consistency.py)")
    unjudged: Unjudged | None = Field(
        default=None, description="why the window has no decision (None: judged, or a "
                                  "decision was possible)")
    integrity_unjudged: Unjudged | None = Field(
        default=None, description="why the H_i the observer reported at the window's end was "
                                  "not judged for data integrity (None: judged, or none came)")
    scan_z_max: float | None = Field(
        default=None, ge=0.0,
        description="the sequential test's largest scan statistic max_n |Z_n| at the window's "
                    "images it scored (docs/fdir.md, 'The sequential test'); None: none scored "
                    "or the window test alone")
    scan_threshold: float | None = Field(
        default=None, gt=0.0, description="the threshold c the scan statistic is held to")
    nis_scan_z_max: float | None = Field(
        default=None, ge=0.0,
        description="the NIS scan's largest statistic at the window's nav updates (None: none "
                    "scored, or the window test alone)")
    nis_scan_threshold: float | None = Field(
        default=None, gt=0.0, description="the threshold c_nis the NIS scan is held to")
    image_sigma: float | None = Field(
        default=None, ge=0.0,
        description="one image's nominal relative 1σ √(σ_b² + σ_e²), RMS over the images "
                    "scored (the per-image divergence of a shift δ is δ² / 2σ²)")
    evidence_since_s: float | None = Field(
        default=None,
        description="the evidence is of the window's images from this time on (s): the change "
                    "the sequential test estimated, for a fault it declared within the window "
                    "(docs/fdir.md, 'Identification after a crossing'); None: the whole window")


class ScanStatus(Message):
    """The sequential test's evidence on one observer as it is scored (docs/fdir.md, "What
    the operator sees"), one at most per observer and ground step with something new: at
    ``t_sim`` (the newest image or nav update scored, s), the image scan's statistic
    max_n |Z_n| at its newest image and its threshold c, and the NIS scan's max_n z_n at its
    newest update and its threshold c_nis.  A fault is declared when either crosses (None:
    not scored yet in the window being collected)."""

    spacecraft: int = Field(ge=1)
    image_z: float | None = Field(default=None, ge=0.0)
    image_threshold: float | None = Field(default=None, gt=0.0)
    nis_z: float | None = Field(default=None)
    nis_threshold: float | None = Field(default=None, gt=0.0)


class ConstellationWindow(Message):
    """The global check (Eq. 6) over one FDI window (ground/fdir/constellation.py): the
    constellation ratio ΣΔH_i / ΣΔH_i^pred of the judged observers, its nominal mean and 1σ,
    the threshold, whether it was exceeded, the observer that alone explains an excess (None:
    none does, or not exceeded) and whether the excess is common mode; the ground's cost H at
    the window's start (Eq. 4) and the running shortfall Σ(ΔH^pred − ΔH) (Eq. 6's H − H_nom to
    first order).  None where fewer than three observers were judged."""

    t_start_s: Time
    t_end_s: Time
    observers: int = Field(ge=0)
    ratio: float | None = None
    ratio_mean: float | None = None
    ratio_std: float | None = None
    threshold: float | None = None
    exceeded: bool | None = None
    explained_by: int | None = None
    common_mode: bool | None = None
    cost: float
    shortfall: float


class FaultReport(Message):
    """A fault declared by the ground FDIR: the observer, its identified class (None: not
    identified), the direction, the metric and threshold of the window that declared it, and
    the evidence behind the class."""

    spacecraft: int = Field(ge=0, description="the faulty observer; 0: the constellation")
    fault_class: Literal["actuator", "camera", "state_sensor", "link", "data_integrity",
                         "common_mode"] | None
    direction: Literal["improved", "degraded"] | None = None
    metric: float | None = None
    threshold: float | None = None
    window_end_s: Time
    evidence: dict[str, float] = Field(default_factory=dict, max_length=32)
    cause: Literal["store_overflow"] | None = Field(
        default=None, description="a link fault's known cause: the observer's onboard store "
                                  "overflowed (ground passes), not a fault of the observer")
    declared_s: Time | None = Field(
        default=None, description="when the ground judged the window and declared, s: "
                                  "fdir.latency_s after its end, or, with ground passes, "
                                  "once its data came down")
    detector: Literal["window", "sequential"] = Field(
        default="window", description="what declared it: a window's tests, or the sequential "
                                      "test at an image (then t_sim is the image's time, "
                                      "metric the span's mean shift and threshold the shift "
                                      "it had to exceed)")


class BaselineVerdict(Message):
    """A baseline detector's verdict on one observer over one FDI window [t_start_s, t_end_s)
    (ground/fdir/baselines.py): its statistic against its threshold, whether that was exceeded
    (None: no decision) and whether this window declared a fault (``alarm``).  ``window``: the
    window test alone (Eq. 9 per window, with its fused tests), published where the sequential
    test is the main detector."""

    detector: Literal["chi2_nis", "cusum", "fixed_threshold", "window"]
    spacecraft: int = Field(ge=1)
    t_start_s: Time
    t_end_s: Time
    statistic: float | None = None
    threshold: float | None = None
    exceeded: bool | None = None
    alarm: bool = False


class AssignmentDecision(Message):
    """The ground's information-driven orbit choice (ground/planning/mission_plan.py): the greedy
    set, its expected information gain and online bound, the expected gain of keeping the current
    PROs, the measured H decrease per check window that led to it, and whether it was flown."""

    phase: str = Field(max_length=64)
    reason: Literal["phase", "saturated", "recovery"]
    library_indices: list[int] = Field(
        description="candidate PRO of observer 1, 2, ... (-1: kept its PRO, dropped from the task)")
    expected_gain: float = Field(ge=0.0)
    upper_bound: float = Field(ge=0.0)
    ratio_bound: float = Field(ge=0.0, le=1.0, description="expected_gain / upper_bound")
    current_gain: float | None = Field(default=None, ge=0.0)
    measured_gains: list[float]
    switched: bool


class TelemetryStatus(Message):
    """Ground view of each spacecraft's telemetry: received, sequence gaps, last time seen,
    navigation filter restarts."""

    class Entry(BaseModel):
        model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
        spacecraft: int
        received: int = 0
        seq_gaps: int = Field(default=0, description="messages missing by sequence count")
        last_t_sim: float | None = None
        stale: bool = False
        nav_resets: int = Field(default=0, ge=0,
                                description="navigation filter restarts (StateEstimate.resets)")
        outages: list[Annotated[list[float], Field(min_length=2, max_length=2)]] = Field(
            default_factory=list, max_length=100,
            description="[last heard, heard again] (sim s) of each silence that ended")

    entries: list[Entry]


class NeighbourRuling(Message):
    """The ground's ruling on a fault its observers' neighbours declared (``NeighbourDeclaration``)
    once it has judged the subject's window itself: ``upheld`` (it declared too) or
    ``overruled`` (it found the window nominal; the observers fuse the subject's observations
    again).  The ground's decision stands over the neighbours'."""

    subject: int = Field(ge=1)
    window_end_s: Time
    verdict: Literal["upheld", "overruled"]
