"""Message models exchanged on the bus (pydantic v2, JSON on the wire).

Every message carries the sender node (``"sim"``, ``"ground"``, ``"sc<N>"``), a sequence
number that the Bus assigns per key expression on publish (like a CCSDS packet sequence
count per APID), and the simulation time ``t_sim`` in seconds.  ``t_wall`` is the publisher's
wall-clock time (UNIX seconds) and is the only field that differs between two runs of the same
scenario and seed.

Non-finite floats (NaN, inf) are rejected on construction and on receipt: a message carrying
one is invalid, is dropped and counted.  Unknown fields are rejected too.
"""

from __future__ import annotations

import math
from typing import Annotated, ClassVar, Literal, get_args

import numpy as np
import numpy.typing as npt
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, model_validator

# --- physical ranges ----------------------------------------------------------------------
# What a message may carry, far beyond anything the mission flies and far below what breaks a
# filter: a value outside is refused where it enters (an invalid message, dropped and counted).

MAX_RANGE_M = 1.0e5
"""Largest relative position component, m (the HCW model is meaningless long before)."""
MAX_SPEED_MPS = 1.0e3
"""Largest relative velocity component, m/s."""
MAX_ACCEL_MPS2 = 10.0
"""Largest commanded or planned acceleration component, m/s²."""
MAX_RATE_RADPS = 10.0
"""Largest body rate or gyro bias component, rad/s."""
MAX_FORCE_N = 10.0
"""Largest thrust command component, N (the thrusters give tens of mN)."""
MAX_TORQUE_NM = 1.0
"""Largest torque command component, N·m (the wheels give a few mN·m)."""
MAX_TIME_S = 1.0e8
"""Latest simulation time a message may carry, s (three years)."""
MAX_PRECISION = 1.0e12
"""Largest per-POI precision (information, 1/m²)."""
MAX_ANGLE_RAD = math.pi
"""Largest angle or angular 1σ, rad."""


def _vector(n: int, limit: float) -> type[list[float]]:
    """A list of n floats, each within ±limit."""
    item = Annotated[float, Field(ge=-limit, le=limit)]
    return Annotated[list[item], Field(min_length=n, max_length=n)]  # type: ignore[valid-type,return-value]


Position = _vector(3, MAX_RANGE_M)
"""LVLH position, m."""
Velocity = _vector(3, MAX_SPEED_MPS)
"""LVLH velocity, m/s."""
Accel = _vector(3, MAX_ACCEL_MPS2)
"""LVLH acceleration, m/s²."""
Rate = _vector(3, MAX_RATE_RADPS)
"""Body rate, rad/s."""
Force = _vector(3, MAX_FORCE_N)
"""Body force, N."""
Torque = _vector(3, MAX_TORQUE_NM)
"""Body torque, N·m."""
State6 = _vector(6, MAX_RANGE_M)
"""[x y z vx vy vz] (m, m/s); StateEstimate holds the velocity part to MAX_SPEED_MPS."""
Quat = _vector(4, 1.0 + 1e-9)
"""Quaternion, scalar last [x, y, z, w] (scipy and Foxglove convention)."""
Mat6 = Annotated[list[_vector(6, MAX_RANGE_M**2)], Field(  # type: ignore[valid-type]
    min_length=6, max_length=6)]
"""6x6 covariance (m², m²/s, m²/s²)."""
Time = Annotated[float, Field(ge=0.0, le=MAX_TIME_S)]
"""Simulation time, s."""
Angle = Annotated[float, Field(ge=0.0, le=MAX_ANGLE_RAD)]
"""Non-negative angle or angular 1σ, rad."""
RateGroupName = Literal["high", "mid", "low"]


class Message(BaseModel):
    """Base of every bus message.  Immutable once built (the in-process bus hands the same
    object to every subscriber); the Bus stamps sender, seq and t_wall on publish (``stamp``)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)
    WALL_CLOCK_FIELDS: ClassVar[frozenset[str]] = frozenset({"t_wall"})
    """Fields that measure the wall clock (not reproducible); subclasses may add their own."""

    sender: str = Field(max_length=64, description="node that published the message")
    seq: int = Field(default=0, ge=0, description="per-key sequence count, set by the Bus")
    t_sim: float = Field(ge=0.0, le=MAX_TIME_S, description="simulation time of the message, s")
    t_wall: float = Field(default=0.0,
                          description="publisher wall clock, UNIX s (not reproducible)")


def stamp(msg: Message, sender: str, seq: int, t_wall: float) -> None:
    """Set the Bus's fields of a message being published (the one write to a frozen message:
    the values are the Bus's own, valid by construction)."""
    fields = msg.__dict__
    fields["sender"], fields["seq"], fields["t_wall"] = sender, seq, t_wall
    msg.__pydantic_fields_set__.update(("sender", "seq", "t_wall"))


# --- time and lockstep -----------------------------------------------------------------------


class Tick(Message):
    """Tick k from the sim (the time master): nodes run their rate groups for t_sim = k*dt.

    ``expect`` maps each key published since the previous tick to its last sequence number; a
    receiver waits until it holds those of its subscriptions before it runs the tick, so message
    arrival order never changes the result (determinism across transports).
    """

    k: int = Field(ge=0)
    dt_s: float = Field(gt=0.0)
    expect: dict[str, int] = Field(default_factory=dict)
    final: bool = Field(default=False, description="last tick of the run")
    rejoin: list[str] = Field(
        default_factory=list,
        description="participants the sim lost and sees again, until each answers a tick: "
                    "such a node takes this tick as its own next one, however far ahead")


class TickDone(Message):
    """A node's answer to tick k: it has run its groups; ``published`` as in Tick.expect."""

    k: int = Field(ge=0)
    published: dict[str, int] = Field(default_factory=dict)


class SimStatus(Message):
    """Lifecycle of the run, from the sim: ``running`` then ``finished`` (nodes then exit);
    ``participants``: the nodes lost from the lockstep (process died, stalled, disconnected) and
    rejoined, with their sim times."""

    class Event(BaseModel):
        model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)
        what: Literal["lost", "rejoined"]
        t_sim: float = Field(ge=0.0, le=MAX_TIME_S)

    state: Literal["waiting", "running", "finished", "aborted"]
    k: int = Field(default=0, ge=0)
    reason: str = ""
    rejected_commands: int = Field(
        default=0, ge=0, description="actuator commands refused (stale, future or wrong sender)")
    participants: dict[str, list[Event]] = Field(default_factory=dict, max_length=64)


# --- sim truth and sensors -------------------------------------------------------------------


class TruthState(Message):
    """True relative states of all observers in the target's LVLH frame (x radial, y along-track,
    z cross-track).  Used by the channel model (range) and archived as truth for evaluation.

    ``q_lvlh_body``: true attitude, the rotation taking body vectors into LVLH; ``w_body_radps``:
    true inertial angular velocity in body axes; ``dv_mps``: velocity increment delivered by the
    thrusters since the start, L1 over the body axes (Σ_j |F_j|/m·dt, what the propellant pays
    for), m/s.  Empty when the sim has no attitude.
    """

    spacecraft: list[int]
    r_lvlh_m: list[Position]
    v_lvlh_mps: list[Velocity]
    q_lvlh_body: list[Quat] = Field(default_factory=list)
    w_body_radps: list[Rate] = Field(default_factory=list)
    dv_mps: list[float] = Field(default_factory=list)


class RelNavMeasurement(Message):
    """Relative position/velocity sensor of one observer (LVLH, noisy, seeded)."""

    spacecraft: int = Field(ge=1)
    r_m: Position
    v_mps: Velocity
    sigma_r_m: float = Field(gt=0.0, le=MAX_RANGE_M)
    sigma_v_mps: float = Field(gt=0.0, le=MAX_SPEED_MPS)


class AttitudeMeasurement(Message):
    """Attitude sensors of one observer at ω_high: gyro rate (body axes, rad/s, averaged over the
    last tick) and, when the star tracker has a fix this tick, its measured attitude
    (rotation body -> ECI, scalar last) with its 1σ noise about the cross-boresight and boresight
    axes (rad)."""

    spacecraft: int = Field(ge=1)
    gyro_radps: Rate
    star_tracker: Quat | None = None
    st_sigma_cross_rad: Angle = 0.0
    st_sigma_roll_rad: Angle = 0.0

    @model_validator(mode="after")
    def _fix_is_usable(self) -> AttitudeMeasurement:
        if self.star_tracker is not None:
            if abs(math.sqrt(sum(c * c for c in self.star_tracker)) - 1.0) > 1e-3:
                raise ValueError("star_tracker must be a unit quaternion")
            if self.st_sigma_cross_rad <= 0.0 or self.st_sigma_roll_rad <= 0.0:
                raise ValueError("a star-tracker fix needs positive st_sigma_* (rad)")
        return self


_MAX_POIS = 1_000_000
"""Most POIs one image or observations message may carry."""


def _header_ok(sender: object, t_sim: object) -> bool:
    """Whether ``sender`` and ``t_sim`` pass :class:`Message`'s rules."""
    return (type(sender) is str and len(sender) <= 64 and type(t_sim) is float
            and 0.0 <= t_sim <= MAX_TIME_S)


class _PoiPrecisions(Message):
    """POI indices (into the target's POI list) and the precision σ⁻¹ measured on each."""

    spacecraft: int = Field(ge=1)
    poi: list[Annotated[int, Field(ge=0)]] = Field(max_length=_MAX_POIS)
    precision: list[Annotated[float, Field(ge=0.0, le=MAX_PRECISION)]] = Field(
        max_length=_MAX_POIS)

    _arrays: tuple[list[int], np.ndarray, np.ndarray] | None = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _same_length(self) -> _PoiPrecisions:
        if len(self.poi) != len(self.precision):
            raise ValueError("poi and precision must have the same length")
        return self

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """``poi`` (int64) and ``precision`` (float64) as read-only numpy arrays, converted once
        per message: in one process every subscriber of the same message shares them."""
        cached = self._arrays
        if cached is None or cached[0] is not self.poi:  # a model_copy may carry another list
            self._keep_arrays(self.poi, self.precision)
            cached = self._arrays
            assert cached is not None
        return cached[1], cached[2]

    def _keep_arrays(self, poi: npt.ArrayLike, precision: npt.ArrayLike) -> None:
        """Keep read-only copies of ``poi`` (int64) and ``precision`` (float64), equal to the
        lists, as what :meth:`arrays` returns."""
        idx = np.array(poi, dtype=np.int64)
        prec = np.array(precision, dtype=np.float64)
        idx.setflags(write=False)
        prec.setflags(write=False)
        self.__pydantic_private__["_arrays"] = (self.poi, idx, prec)  # type: ignore[index]


class CameraImage(_PoiPrecisions):
    """One inspection image of an observer (ω_mid): the POIs it saw (ascending) and the
    precision of each measurement (Eq. 5: 1/(k·dist²), with the camera's noise and health)."""

    @classmethod
    def of_arrays(cls, sender: str, t_sim: float, spacecraft: int, poi: np.ndarray,
                  precision: np.ndarray) -> CameraImage:
        """The image of ``poi`` (int) and ``precision`` (float) arrays, which keeps copies of
        them as :meth:`arrays` (the same values: its subscribers convert no list back).

        Validated on the arrays: the schema's rules checked with numpy (POIs integers ≥ 0,
        precisions finite in [0, MAX_PRECISION], equal lengths within the bound, the header's
        ranges), ~20× cheaper than pydantic on a 2,500-POI image; whatever those checks do not
        pass is validated by pydantic, which raises (``tests/test_encoding.py``)."""
        idx, prec = np.asarray(poi), np.asarray(precision)
        fields = {"sender": sender, "t_sim": t_sim, "spacecraft": spacecraft,
                  "poi": idx.tolist(), "precision": prec.tolist()}
        ok = (_header_ok(sender, t_sim) and type(spacecraft) is int and spacecraft >= 1
              and idx.ndim == prec.ndim == 1 and len(idx) == len(prec) <= _MAX_POIS
              and np.issubdtype(idx.dtype, np.integer) and bool((idx >= 0).all())
              and np.issubdtype(prec.dtype, np.floating) and bool(np.isfinite(prec).all())
              and bool(((prec >= 0.0) & (prec <= MAX_PRECISION)).all()))
        msg = cls.model_construct(**fields) if ok else cls(**fields)
        msg._keep_arrays(idx, prec)
        return msg


# --- commands (flight software -> hardware) --------------------------------------------------


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


# --- flight software -------------------------------------------------------------------------


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


class FaultEvent(Message):
    """Truth of an injected fault (sim): ``kind`` on ``spacecraft`` switched on or off at
    ``t_sim``, with the scenario's ``magnitude`` and the realised parameters (``detail``:
    directions, torques, rotations; see sim/faults.py); spacecraft 0: every observer."""

    spacecraft: int = Field(ge=0)
    kind: str = Field(max_length=64)
    active: bool
    magnitude: float | None = None
    start_s: float = Field(ge=0.0)
    end_s: float | None = None
    detail: dict[str, list[float] | float] = Field(default_factory=dict)


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
                                  "(ground/fdir/hardware_threshold.py)")
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
    failed: list[WindowTest] = Field(
        default_factory=list, max_length=len(WINDOW_TESTS),
        description="the detector's tests this window failed (ground/fdir/consistency.py)")


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


class BaselineVerdict(Message):
    """A baseline detector's verdict on one observer over one FDI window [t_start_s, t_end_s)
    (ground/fdir/baselines.py): its statistic against its threshold, whether that was exceeded
    (None: no decision) and whether this window declared a fault (``alarm``)."""

    detector: Literal["chi2_nis", "cusum", "fixed_threshold"]
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


class TransferPlanMsg(Message):
    """A planned transfer (SCP, L1 fuel): node times (s, mission time), LVLH states (m, m/s) and
    ZOH accelerations (m/s², one per interval) — the nominal plan the ground's twin replays."""

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


class GuidanceStatus(Message):
    """Guidance state of one observer at ω_low: mode, current assignment, tracking error of the
    estimate against the reference (m, m/s), the acceleration commanded (LVLH, m/s²), Δv
    commanded so far (m/s, Σ|u|₁·dt) and the MPC solver status and time."""

    WALL_CLOCK_FIELDS: ClassVar[frozenset[str]] = frozenset({"t_wall", "mpc_ms"})

    spacecraft: int = Field(ge=1)
    mode: Literal["idle", "transfer", "hold"]
    assignment_id: int = Field(default=0, ge=0)
    phase: str = ""
    pos_error_m: float = Field(default=0.0, ge=0.0)
    vel_error_mps: float = Field(default=0.0, ge=0.0)
    accel_lvlh_mps2: Accel = Field(default_factory=lambda: [0.0, 0.0, 0.0])
    dv_commanded_mps: float = Field(default=0.0, ge=0.0)
    mpc_status: str = ""
    mpc_ms: float = Field(default=0.0, ge=0.0)


class PoiObservations(_PoiPrecisions):
    """The observations of one image of ``spacecraft`` (taken at ``image_t_s``) as shared with
    the other observers and the ground.  Received only within range."""

    image_t_s: Time

    @classmethod
    def of_image(cls, image: CameraImage, sender: str, t_sim: float) -> PoiObservations:
        """The observations of ``image``, sent by ``sender`` at ``t_sim`` (s): the image's own
        validated, immutable lists, not validated again (``model_construct`` of valid parts;
        a 2,500-POI image's lists cost ~0.1 ms to validate).  A header outside the rules goes
        to pydantic, which raises."""
        fields = {"sender": sender, "t_sim": t_sim, "spacecraft": image.spacecraft,
                  "image_t_s": image.t_sim, "poi": image.poi, "precision": image.precision}
        msg = cls.model_construct(**fields) if _header_ok(sender, t_sim) else cls(**fields)
        msg.__pydantic_private__["_arrays"] = image._arrays  # type: ignore[index]
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


class Heartbeat(Message):
    """Node liveness and identity, at ω_mid."""

    node: str
    apps: list[str]
    k: int = Field(ge=0)


class GroupStats(BaseModel):
    """Execution statistics of one rate group."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    runs: int = 0
    cycle_slips: int = Field(default=0, description="runs longer than the group's budget")
    max_exec_ms: float = 0.0
    budget_ms: float = 0.0


class ExecStats(Message):
    """Executive statistics: cycle slips per rate group, app errors, invalid messages dropped,
    messages refused at admission (``interfaces.runtime.admission``: a sender not owning its key, an
    absurd sequence number or date, a full queue, an implausible tick)."""

    node: str
    groups: dict[str, GroupStats]
    app_errors: int = 0
    invalid_dropped: int = 0
    refused: int = 0
    barrier_timeouts: int = 0
    ticks: int = 0


class LinkCounter(BaseModel):
    """Counters of one directed link src -> dst (messages offered to the channel)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    src: str
    dst: str
    sent: int = 0
    delivered: int = 0
    dropped_range: int = 0
    dropped_loss: int = 0
    dropped_cut: int = 0


class LinkStats(Message):
    """Per-link counters of the receiving node's channel model."""

    node: str
    links: list[LinkCounter]


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


ALL_MESSAGES: tuple[type[Message], ...] = (
    Tick,
    TickDone,
    SimStatus,
    TruthState,
    RelNavMeasurement,
    AttitudeMeasurement,
    ThrustCommand,
    WheelCommand,
    StateEstimate,
    ProAssignments,
    AssignmentDecision,
    FaultEvent,
    FdirWindow,
    FaultReport,
    ConstellationWindow,
    BaselineVerdict,
    TransferPlanMsg,
    GuidanceStatus,
    PointingTarget,
    AttitudeEstimate,
    CameraImage,
    PoiObservations,
    InfoCostTelemetry,
    Heartbeat,
    ExecStats,
    LinkStats,
    TelemetryStatus,
)


def registry() -> dict[str, type[Message]]:
    """Message type name -> model, for decoding by name (recorder, telemetry, schema server)."""
    return {m.__name__: m for m in ALL_MESSAGES}


def json_schema(msg_type: type[Message]) -> dict[str, object]:
    """JSON schema of a message type (the form written to MCAP and served on the bus)."""
    return msg_type.model_json_schema()
