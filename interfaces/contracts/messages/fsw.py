"""Messages the flight software publishes: actuator commands, nav and attitude estimates,
guidance status and transfer plans, observations and the information cost it reports."""

from __future__ import annotations

import math
from typing import ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field, NonNegativeInt, model_validator

from interfaces.contracts.messages.base import (
    MAX_SPEED_MPS,
    Accel,
    Angle,
    Force,
    Mat6,
    Message,
    Momentum,
    PoiPrecisions,
    Position,
    Quat,
    Rate,
    State6,
    Time,
    Torque,
    Unjudged,
    Velocity,
    header_ok,
)
from interfaces.contracts.messages.ground import ProElements
from interfaces.contracts.messages.sim import CameraImage


class ThrustCommand(Message):
    """Thruster command of one observer: force in body axes (N) to hold for ``duration_s`` from
    ``t_sim`` (then zero).  The hardware clips each axis to its limit and drops impulses below the
    minimum impulse bit."""

    spacecraft: int = Field(ge=1)
    force_body_n: Force
    duration_s: float = Field(gt=0.0, le=3600.0)


class WheelCommand(Message):
    """Reaction-wheel command of one observer: torque on the body (body axes, N·m), held until the
    next command (the wheels realise it as dh/dt = -torque, within their torque and momentum
    limits)."""

    spacecraft: int = Field(ge=1)
    torque_body_nm: Torque


class StateEstimate(Message):
    """Navigation filter output: relative state [x, y, z, vx, vy, vz] (m, m/s, LVLH) and its 6x6
    covariance; ``nis`` is the normalized innovation squared of this step's measurement update
    (chi-square, 6 dof), None when the step had none."""

    spacecraft: int = Field(ge=1)
    x: State6
    P: Mat6
    nis: float | None = Field(default=None, ge=0.0)
    resets: int = Field(default=0, ge=0, description="times the filter has diverged and "
                        "restarted from a measurement")

    @model_validator(mode="after")
    def _velocity_in_range(self) -> StateEstimate:
        if max(abs(v) for v in self.x[3:]) > MAX_SPEED_MPS:
            raise ValueError(f"velocity beyond {MAX_SPEED_MPS} m/s")
        return self

    def position_sigma_m(self) -> float:
        """The position's 1σ per axis, m: √(trace P_rr / 3) (the ground's FDIR and the pose an
        observer shares with its observations both read it)."""
        p = self.P
        return math.sqrt(max((p[0][0] + p[1][1] + p[2][2]) / 3.0, 0.0))


class TransferPlanMsg(Message):
    """A planned transfer (SCP, L1 fuel): node times (s, mission time), LVLH states (m, m/s) and
    ZOH accelerations (m/s², one per interval) — the nominal plan the ground's twin replays;
    or, when not solved (``refused``), the spacecraft's refusal of the assignment."""

    WALL_CLOCK_FIELDS: ClassVar[frozenset[str]] = frozenset({"t_wall", "solve_ms"})

    spacecraft: int = Field(ge=1)
    assignment_id: int = Field(ge=1)
    t_s: list[Time]
    x: list[State6]
    u_mps2: list[Accel]
    dv_mps: float = Field(ge=0.0, description="planned L1 fuel, Σ|u|·h, m/s")
    status: str
    iterations: int = Field(ge=0)
    min_range_m: float = Field(ge=0.0)
    solve_ms: float = Field(ge=0.0)

    @property
    def refused(self) -> bool:
        """The spacecraft found no plan meeting every constraint (``status`` other than
        ``"solved"``; no nodes when it could not plan at all): it refused the assignment and
        keeps flying its previous one."""
        return self.status != "solved"


class GuidanceStatus(Message):
    """Guidance state of one observer at ω_low: mode (``safe``: the onboard FDIR's safe hold,
    no thrust until a newer assignment), current assignment, tracking error of the
    estimate against the reference (m, m/s), the acceleration commanded (LVLH, m/s²), Δv
    commanded so far (m/s, Σ|u|₁·dt) and the MPC solver status and time."""

    WALL_CLOCK_FIELDS: ClassVar[frozenset[str]] = frozenset({"t_wall", "mpc_ms"})

    spacecraft: int = Field(ge=1)
    mode: Literal["idle", "transfer", "hold", "safe"]
    assignment_id: int = Field(default=0, ge=0)
    phase: str = ""
    pos_error_m: float = Field(default=0.0, ge=0.0)
    vel_error_mps: float = Field(default=0.0, ge=0.0)
    accel_lvlh_mps2: Accel = Field(default_factory=lambda: [0.0, 0.0, 0.0])
    dv_commanded_mps: float = Field(default=0.0, ge=0.0)
    mpc_status: str = ""
    mpc_ms: float = Field(default=0.0, ge=0.0)
    pro: ProElements | None = Field(
        default=None, description="the PRO of the assignment it flies (None: none): with the "
                                  "assignment id and the mode, the plan its neighbours judge it "
                                  "against (docs/fdir.md, \"Neighbours judge each other\")")


class ReportedPose(BaseModel):
    """Where an observer says it was and where its camera aimed when it took an image (its
    nav and attitude estimates then): what a neighbour judging it needs of it besides the
    observations (docs/fdir.md, "Neighbours judge each other")."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)
    nav_m: Position = Field(description="estimated LVLH position, m")
    nav_sigma_m: float = Field(ge=0.0, le=1e6, description="its 1σ per axis, m")
    aim_m: Position = Field(description="the pointing target, LVLH, m")
    knowledge_rad: Angle = Field(description="attitude knowledge, 1σ, rad")
    tracking_rad: Angle = Field(description="the estimated pointing error, rad")
    tracking_s: float = Field(ge=0.0, description="time in track mode (0: not tracking), s")


class PoiObservations(PoiPrecisions):
    """The observations of one image of ``spacecraft`` (taken at ``image_t_s``) as shared with
    the other observers and the ground.  Received only within range.  With the neighbours'
    FDIR on, each carries the observer's reported pose (``pose``)."""

    image_t_s: Time
    pose: ReportedPose | None = None

    @classmethod
    def of_image(cls, image: CameraImage, sender: str, t_sim: float,
                 pose: ReportedPose | None = None) -> PoiObservations:
        """The observations of ``image``, sent by ``sender`` at ``t_sim`` (s): the image's own
        validated, immutable lists, not validated again (``model_construct`` of valid parts;
        a 2,500-POI image's lists cost ~0.1 ms to validate).  A header outside the rules goes
        to pydantic, which raises."""
        fields = {"sender": sender, "t_sim": t_sim, "spacecraft": image.spacecraft,
                  "image_t_s": image.t_sim, "poi_packed": image.poi_packed,
                  "precision_packed": image.precision_packed}
        if pose is not None:
            fields["pose"] = pose
        msg = cls.model_construct(**fields) if header_ok(sender, t_sim) else cls(**fields)
        msg.share_arrays(image)
        return msg


class InfoCostTelemetry(Message):
    """Information-cost telemetry of one observer at the FDI period (Eq. 8): its contribution
    H_i, the information cost H and the prior term of its fused view (H = prior + Σ_j H_j),
    the POIs it has seen, and the observers whose observations it has fused."""

    spacecraft: int = Field(ge=1)
    h_i: float = Field(ge=0.0)
    h_local: float = Field(ge=0.0)
    prior_term: float = Field(ge=0.0)
    contributions: dict[str, float] = Field(default_factory=dict,
                                            description="H_j by spacecraft id, as fused here")
    pois_seen_own: int = Field(ge=0)
    pois_seen_fused: int = Field(ge=0)
    images: int = Field(ge=0)
    shared_received: int = Field(ge=0)
    shared_by: dict[str, NonNegativeInt] = Field(
        default_factory=dict, max_length=256,
        description="the neighbours' images fused here, by spacecraft id (the ground rebuilds "
                    "this observer's view from them: docs/fdir.md, \"Link and data faults\")")


class PointingTarget(Message):
    """Where the camera wants the boresight: a point in LVLH (m) at ``t_sim``, moving at
    ``target_rate_lvlh_mps`` (m/s) with ``target_accel_lvlh_mps2`` (m/s²) — from the camera app;
    the attitude app extrapolates it and uses its motion as feed-forward."""

    spacecraft: int = Field(ge=1)
    target_lvlh_m: Position
    target_rate_lvlh_mps: Velocity = Field(default_factory=lambda: [0.0, 0.0, 0.0])
    target_accel_lvlh_mps2: Accel = Field(default_factory=lambda: [0.0, 0.0, 0.0])


class AttitudeEstimate(Message):
    """Attitude determination and control state of one observer: estimated attitude (body ->
    ECI and body -> LVLH, scalar last), gyro bias (rad/s) and 1σ attitude uncertainty (rad);
    the pointing target (LVLH, m), the estimated pointing error (rad), the controller mode and
    the commanded torque (N·m)."""

    spacecraft: int = Field(ge=1)
    q_eci_body: Quat
    q_lvlh_body: Quat
    gyro_bias_radps: Rate
    sigma_att_rad: Angle
    target_lvlh_m: Position
    pointing_error_rad: Angle
    mode: Literal["init", "slew", "track"]
    torque_body_nm: Torque
    nis: float | None = None
    wheel_momentum_nms: Momentum | None = Field(
        default=None, description="the wheels' momentum as the app integrates its commands, "
                                  "body axes, N·m·s (absent from archives before it existed)")
    star_tracker_age_s: float | None = Field(
        default=None, ge=0.0, description="time since the last star-tracker attitude, s "
                                          "(None: none yet)")


OnboardCommandName = Literal["safe_hold", "point_target", "camera_off", "nav_reset"]
"""What the onboard FDIR's stored sequences command (fsw/lib/onboard_fdir.py)."""
OnboardEventName = Literal["trip", "clear", "report", "sequence", "recovered", "plan_request"]
FaultClassName = Literal["actuator", "camera", "state_sensor", "link", "data_integrity",
                         "common_mode"]


class OnboardCommand(Message):
    """One command of a stored sequence of the onboard FDIR (fsw/apps/fdir.py) to an app of its
    own spacecraft: ``safe_hold`` (guidance: thrust off, no transfer, until an assignment newer
    than ``assignment_id``), ``point_target`` (camera: aim at the target's centre),
    ``camera_off`` (camera: no more observations), ``nav_reset`` (nav: restart the filter from
    the next measurement)."""

    spacecraft: int = Field(ge=1)
    command: OnboardCommandName
    sequence: str = Field(max_length=32, description="the stored sequence it belongs to")
    assignment_id: int = Field(default=0, ge=0, description="safe_hold: the assignment in force")


class OnboardFdirEvent(Message):
    """An event of the onboard FDIR (fsw/apps/fdir.py), as cFS's event messages: a watchpoint
    tripped or cleared (``name``, its ``value`` and ``limit``), a ground FaultReport naming this
    spacecraft received (``fault_class``), a stored sequence started (``name``, ``detail``: its
    commands), safe hold ended by a new assignment (``recovered``), a new plan asked of the
    ground (``plan_request``; ``name`` ``safe_hold`` when asked from safe hold)."""

    spacecraft: int = Field(ge=1)
    event: OnboardEventName
    name: str = Field(default="", max_length=32)
    value: float | None = None
    limit: float | None = None
    fault_class: FaultClassName | None = None
    detail: str = Field(default="", max_length=200)


class NeighbourVerdict(BaseModel):
    """One neighbour's window as judged aboard another observer (Eq. 9 on the judge's fused
    map): ΔH_j of its shared observations, the twin's ΔH_j^pred on its assigned PRO, H_m
    against τ from the hardware model; ``exceeded`` None when the window could not decide."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)
    subject: int = Field(ge=1)
    images: int = Field(ge=0)
    dh: float | None = None
    dh_pred: float | None = None
    metric: float | None = None
    threshold: float | None = None
    exceeded: bool | None = None
    direction: Literal["improved", "degraded"] | None = None
    failed: list[Literal["information", "plan", "pointing"]] = Field(
        default_factory=list, max_length=3, description="the tests the window failed")
    unjudged: Unjudged | None = Field(default=None,
                                      description="why the window has no decision (None: judged)")


class NeighbourCrossing(BaseModel):
    """A neighbour's image scan crossing its threshold aboard the judge, mid-window
    (``fdir.detector = "sequential"``; ``gnc/image_scan.py``): the image's time, the scan
    statistic and its span, the span's mean relative shift and the shift it had to exceed."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)
    subject: int = Field(ge=1)
    t_s: Time = Field(description="the image at which the scan crossed, sim s")
    z: float = Field(ge=0.0)
    span: int = Field(ge=1, le=64)
    shift: float
    limit: float = Field(ge=0.0)
    direction: Literal["improved", "degraded"]


class NeighbourJudgement(Message):
    """An observer's verdicts on the neighbours it heard over one FDI window [t_start_s,
    t_end_s), shared on the crosslinks (``fsw/apps/neighbours.py``): at the window's end its
    ``verdicts``; with the sequential test, as they happen, its scans' ``crossings``."""

    spacecraft: int = Field(ge=1, description="the judge")
    t_start_s: Time
    t_end_s: Time
    verdicts: list[NeighbourVerdict] = Field(default_factory=list, max_length=64)
    crossings: list[NeighbourCrossing] = Field(default_factory=list, max_length=64)


class NeighbourDeclaration(Message):
    """A fault declared aboard ``spacecraft`` on ``subject`` by its neighbours' agreement over
    the window [t_start_s, t_end_s): ``judges`` found it failed, of ``decided`` that judged it
    (docs/fdir.md, "Neighbours judge each other").  Sent to the ground, which rules on it."""

    spacecraft: int = Field(ge=1, description="where the rule was applied")
    subject: int = Field(ge=1)
    t_start_s: Time
    t_end_s: Time
    judges: list[int] = Field(min_length=1, max_length=64)
    decided: list[int] = Field(min_length=1, max_length=64)
    crossed_s: Time | None = Field(
        default=None, description="declared mid-window on the judges' scans: when the first "
                                  "of them crossed, sim s (None: on the window's verdicts)")
