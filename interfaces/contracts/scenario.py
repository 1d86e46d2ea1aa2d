"""Scenario files (TOML) as pydantic models: the contract of docs/contracts.md ("Scenario TOML").

Every section has defaults, so a scenario states only what differs.  Unknown keys are errors
(a typo must not silently fall back to a default); values are checked for range and
consistency, and errors name the file and the offending field.
"""

from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

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
]
COMMON_MODE_KINDS = frozenset({"camera_calibration"})
"""Fault kinds that act on every observer at once (``spacecraft = 0``): a camera calibration
error (the true variance coefficient is k / ``magnitude``: every precision scaled by it) that no
single observer explains."""


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class Orbit(_Section):
    """Target (chief) orbit: circular at ``altitude_km``."""

    altitude_km: float = Field(default=500.0, gt=100.0, lt=40000.0)
    inclination_deg: float = Field(default=51.6, ge=0.0, le=180.0)
    j2: bool = Field(default=False, description="include J2 in the truth dynamics")


class Target(_Section):
    """The target spacecraft and its points of interest (POIs), spread uniformly on its surface;
    each POI has prior variance ``prior_variance`` (w) and importance 1/``pois`` (φ)."""

    shape: Literal["sphere"] = "sphere"
    radius_m: float = Field(default=5.0, gt=0.0)
    pois: int = Field(default=5000, ge=1)
    prior_variance: float = Field(default=1.0, gt=0.0, description="w, per POI")


class CameraSettings(_Section):
    """The observers' inspection cameras: σ = k·dist² (Eq. 5) within a conical field of view.
    With the defaults (k = 1, the paper's Eq. 22 value, and w = 1) an image at 20 m adds
    1/400 of the prior's information, so one image a second takes the cost down over an orbit
    or two rather than in minutes.

    What an image measures (sim/camera.py): for every POI visible from the camera's TRUE pose
    (inside the cone, within ``max_range_m``, on the side facing the camera) a precision
    σ⁻¹ = β / (k d²) × max(0, 1 + ν ε), with d the TRUE camera-POI distance, β the camera's
    health (1 nominal; < 1 under ``camera_degradation`` or, on every camera at once,
    ``camera_calibration``), ν = ``noise_frac`` and ε ~ N(0, 1) independent per POI and image.
    There is no bias: a nominal camera's precisions are right on average (E[max(0, 1 + ν ε)]
    exceeds 1 by under 0.5% for ν ≤ 0.5), and a systematic error is a fault kind.  Because d is
    the true distance, each image pins the true camera position (``ground/fdir/identify.py``
    locates it to ≈0.25 m at ν = 5%); the ground's hardware threshold and identification take ν
    from this section."""

    half_angle_deg: float = Field(default=20.0, gt=0.0, lt=90.0)
    max_range_m: float = Field(default=200.0, gt=0.0)
    k: float = Field(default=1.0, gt=0.0, description="variance per m² of distance")
    noise_frac: float = Field(default=0.05, ge=0.0, lt=1.0, description="1σ, of each precision")
    pointing: Literal["centre", "max_variance"] = Field(
        default="centre",
        description="camera app's pointing target: the target's centre, or the reachable POI of "
                    "maximum variance (retargets in steps; see fsw/apps/camera.py)")


class Rates(_Section):
    """Rate groups ω_high / ω_mid / ω_low (Hz) and the FDI period (s), a whole number of ω_mid
    periods (``interfaces.contracts.fdi_schedule``)."""

    high_hz: float = Field(default=10.0, gt=0.0)
    mid_hz: float = Field(default=1.0, gt=0.0)
    low_hz: float = Field(default=0.1, gt=0.0)
    fdi_period_s: float = Field(default=30.0, gt=0.0)

    @model_validator(mode="after")
    def _integer_ratios(self) -> Rates:
        for name, hz in (("mid_hz", self.mid_hz), ("low_hz", self.low_hz)):
            ratio = self.high_hz / hz
            if hz > self.high_hz or abs(ratio - round(ratio)) > 1e-9:
                raise ValueError(f"rates.{name} = {hz} must divide rates.high_hz = {self.high_hz}")
        if self.low_hz > self.mid_hz:
            raise ValueError("rates.low_hz must not exceed rates.mid_hz")
        ratio = self.mid_hz / self.low_hz
        if abs(ratio - round(ratio)) > 1e-9:
            raise ValueError(f"rates.low_hz = {self.low_hz} must divide "
                             f"rates.mid_hz = {self.mid_hz}")
        mids = self.fdi_period_s * self.mid_hz
        if round(mids) < 1 or abs(mids - round(mids)) > 1e-9:
            raise ValueError(
                f"rates.fdi_period_s = {self.fdi_period_s} s must be a whole number of ω_mid "
                f"periods ({1.0 / self.mid_hz:g} s at rates.mid_hz = {self.mid_hz}): the "
                "observers report H_i and the ground judges at ω_mid steps, so every FDI window "
                "must end on one")
        return self

    @property
    def dt_s(self) -> float:
        """High-rate tick period, s."""
        return 1.0 / self.high_hz

    def ticks_per(self, group: str) -> int:
        """Ticks between two runs of rate group ``group`` ("high", "mid" or "low")."""
        hz = {"high": self.high_hz, "mid": self.mid_hz, "low": self.low_hz}[group]
        return int(round(self.high_hz / hz))


class Burst(_Section):
    """Gilbert-Elliott burst loss: the average loss rate is ``comms.packet_loss``; losses come in
    bursts of geometric length with this mean (packets)."""

    mean_length_packets: float = Field(ge=1.0)


class LinkCut(_Section):
    """Cut the link between nodes ``a`` and ``b`` ("sc<N>", "ground" or "*" for any) over
    [start_s, end_s)."""

    a: str
    b: str = "*"
    start_s: float = Field(default=0.0, ge=0.0)
    end_s: float = math.inf

    @model_validator(mode="after")
    def _nodes(self) -> LinkCut:
        for n in (self.a, self.b):
            if not re.fullmatch(r"sc\d+|ground|\*", n):
                raise ValueError(f"link cut end {n!r}: expected 'sc<N>', 'ground' or '*'")
        if self.end_s <= self.start_s:
            raise ValueError("link cut end_s must be after start_s")
        return self

    model_config = ConfigDict(extra="forbid", allow_inf_nan=True, frozen=True)


class Comms(_Section):
    """Inter-spacecraft and spacecraft-ground links.  The ground is reached through the target
    spacecraft (the mothership relay at the LVLH origin), so a spacecraft is in ground contact when
    it is within ``range_m`` of the target."""

    range_m: float = Field(default=200.0, gt=0.0)
    packet_loss: float = Field(default=0.0, ge=0.0, lt=1.0)
    burst: Burst | None = None
    delay_s: float = Field(default=0.0, ge=0.0)
    cuts: list[LinkCut] = Field(default_factory=list)


class ObserverOverride(_Section):
    spacecraft: int = Field(ge=1)
    rho_x_m: float | None = None
    alpha_x_deg: float | None = None
    rho_y_m: float | None = None
    rho_z_m: float | None = None
    alpha_z_deg: float | None = None


class _ProFormation(_Section):
    """A set of passive relative orbits, one per observer (HCW form):
    x = ρx sin(nt+αx), y = ρy + 2ρx cos(nt+αx), z = ρz sin(nt+αz), t from the mission start.
    By default spacecraft i of N has αx = αz = phase0_deg + 360°·(i-1)/N; ``overrides`` set any
    parameter of one spacecraft."""

    rho_x_m: float = Field(default=20.0, ge=0.0)
    rho_y_m: float = 0.0
    rho_z_m: float = Field(default=20.0, ge=0.0)
    phase0_deg: float = 0.0
    overrides: list[ObserverOverride] = Field(default_factory=list)

    def pro_of(self, spacecraft: int, count: int) -> tuple[float, float, float, float, float]:
        """(ρx m, αx rad, ρy m, ρz m, αz rad) of ``spacecraft`` (1-based) of ``count``."""
        phase = self.phase0_deg + 360.0 * (spacecraft - 1) / count
        p = {"rho_x_m": self.rho_x_m, "alpha_x_deg": phase, "rho_y_m": self.rho_y_m,
             "rho_z_m": self.rho_z_m, "alpha_z_deg": phase}
        for o in self.overrides:
            if o.spacecraft == spacecraft:
                p.update({k: v for k, v in o.model_dump().items() if v is not None and k in p})
        return (p["rho_x_m"], math.radians(p["alpha_x_deg"]), p["rho_y_m"], p["rho_z_m"],
                math.radians(p["alpha_z_deg"]))


class Observers(_ProFormation):
    """The observers and their initial conditions.  ``start = "pro"``: they start on the PROs of
    this section; ``start = "deploy"``: they are released from the target (Fig. 7, phase 1) at
    ``deploy_radius_m`` from its centre with ``deploy_speed_mps`` outward, directions fanned
    evenly in the along-track/cross-track plane, and drift until the first phase.  The initial
    attitude is drawn from the seed (``initial_attitude = "random"``) or aligned with LVLH, with
    a 1σ tumble rate per axis."""

    count: int = Field(default=5, ge=1, le=64)
    energy_match: bool = Field(default=True, description="match the target's semi-major axis")
    mass_kg: float = Field(default=10.0, gt=0.0)
    inertia_kg_m2: tuple[float, float, float] = Field(
        default=(0.10, 0.12, 0.08), description="principal moments of inertia, kg·m²")
    start: Literal["pro", "deploy"] = "pro"
    deploy_radius_m: float = Field(default=5.0, gt=0.0)
    deploy_speed_mps: float = Field(default=0.05, ge=0.0)
    initial_attitude: Literal["random", "lvlh"] = "random"
    tumble_rate_dps: float = Field(default=0.2, ge=0.0, description="1σ initial rate per axis")

    @model_validator(mode="after")
    def _inertia(self) -> Observers:
        a, b, c = self.inertia_kg_m2
        if min(a, b, c) <= 0 or a + b < c or a + c < b or b + c < a:
            raise ValueError("observers.inertia_kg_m2 must be positive and satisfy the triangle "
                             "inequality of principal moments")
        return self

    def pro(self, spacecraft: int) -> tuple[float, float, float, float, float]:
        """(ρx m, αx rad, ρy m, ρz m, αz rad) of ``spacecraft`` (1-based)."""
        return self.pro_of(spacecraft, self.count)


class Phase(_ProFormation):
    """A phase of the mission plan (Fig. 7): at ``start_s`` every observer leaves its orbit for
    the PRO of this phase, arriving ``transfer_s`` later (fuel-optimal SCP transfer, then held).

    ``assign = "scenario"``: the PROs are the ones given here.  ``assign = "information"``: the
    ground chooses them from the candidate library of ``[assignment]`` by expected information
    gain when the phase is uplinked, and reassigns whenever the gain of the set saturates, until
    the next phase (the PRO fields of the phase are then unused)."""

    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$")
    start_s: float = Field(ge=0.0)
    transfer_s: float = Field(default=900.0, gt=0.0)
    assign: Literal["scenario", "information"] = "scenario"


class AssignmentSettings(_Section):
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


class Actuators(_Section):
    """Thrusters (body-fixed, ± each body axis) and three reaction wheels along the body axes."""

    thruster_max_force_n: float = Field(default=0.02, gt=0.0, description="per axis, N")
    thruster_min_impulse_ns: float = Field(default=1e-4, ge=0.0, description="minimum impulse bit")
    thruster_noise_frac: float = Field(default=0.01, ge=0.0, lt=1.0, description="1σ, of force")
    wheel_max_torque_nm: float = Field(default=2e-3, gt=0.0, description="per wheel, N·m")
    wheel_max_momentum_nms: float = Field(default=0.02, gt=0.0, description="per wheel, N·m·s")


class Guidance(_Section):
    """Orbit guidance: SCP transfers (L1 fuel, keep-out sphere) tracked by MPC at ω_low."""

    keep_out_m: float = Field(default=8.0, gt=0.0, description="keep-out sphere radius d_min, m")
    node_spacing_s: float = Field(default=20.0, gt=0.0, description="SCP interval, s")
    mpc_horizon: int = Field(default=20, ge=2, le=200, description="MPC steps of 1/ω_low")
    plan_thrust_fraction: float = Field(
        default=0.5, gt=0.0, le=1.0,
        description="fraction of the thrust limit the plan may use (the rest is MPC margin)")


class Attitude(_Section):
    """Attitude guidance and control (ω_high): slews planned by SCP, nonlinear tracking."""

    settling_time_s: float = Field(default=30.0, gt=0.0)
    slew_rate_max_dps: float = Field(default=2.0, gt=0.0)
    slew_threshold_deg: float = Field(default=10.0, gt=0.0,
                                      description="errors above this are slewed on a plan")
    boresight_body: tuple[float, float, float] = (0.0, 0.0, 1.0)

    @model_validator(mode="after")
    def _boresight(self) -> Attitude:
        if max(abs(c) for c in self.boresight_body) == 0.0:
            raise ValueError("attitude.boresight_body must be a non-zero vector")
        return self


class Sensors(_Section):
    relnav_sigma_r_m: float = Field(default=0.1, gt=0.0, description="1σ position noise, m")
    relnav_sigma_v_mps: float = Field(default=0.002, gt=0.0, description="1σ velocity noise, m/s")
    gyro_arw_rad_rts: float = Field(default=4.4e-5, ge=0.0,
                                    description="angle random walk σv, rad/√s (0.15°/√h)")
    gyro_bias_rw_rad_s15: float = Field(default=3e-7, ge=0.0,
                                        description="bias random walk σu, rad/s^1.5")
    gyro_bias_sigma_radps: float = Field(default=1e-4, gt=0.0,
                                         description="1σ initial gyro bias, rad/s")
    star_tracker_hz: float = Field(default=1.0, gt=0.0)
    star_tracker_cross_arcsec: float = Field(default=10.0, gt=0.0, description="1σ")
    star_tracker_roll_arcsec: float = Field(default=60.0, gt=0.0, description="1σ, about boresight")


class Nav(_Section):
    q_accel_m2_s3: float = Field(
        default=1e-12, gt=0.0, description="spectral density of unmodelled acceleration, m²/s³"
    )


class FdirSettings(_Section):
    """The ground FDIR (ground/apps/fdir.py, docs/fdir.md): every
    FDI window (``rates.fdi_period_s``) each observer's information gain is compared with the
    nominal twin's prediction (Eq. 9).  The threshold in force (``threshold``) is by default
    the hardware model's (ground/fdir/hardware_threshold.py): the quantile, for
    ``false_alarms_per_observer_hour``, of the ratio's distribution under no fault given the
    camera's noise (``[camera] noise_frac``), the station-keeping accuracy (``track_sigma_m``,
    ``transfer_sigma_m``) plus the nav's reported 1σ, and the pointing jitter
    (``pointing_jitter_deg``) plus the reported attitude knowledge and pointing error (up to
    ``pointing_tol_deg``), propagated through the twin with ``model_samples`` pose draws; or
    Eq. 11-12's (``samples`` pointings within ``eps_deg``).  Both are computed and archived
    every window; ``floor`` is a guard under the one in force.  With ``fuse_guidance`` a window
    also fails on the nav-vs-plan, pointing and Δv-rate tests (ground/fdir/consistency.py:
    ``position_tol_m``, ``pointing_tol_deg``, ``dv_rate_tol_mps2``); with ``fuse_nis`` on the
    nav's normalized innovations.  A fault is declared after ``persistence`` failed windows in
    a row
    (or, with ``persistence_window`` = n, on the window that brings the failures among the last
    n decided windows to ``persistence``); the constellation's ratio (the global check, Eq. 6)
    declares a fault no single observer explains; an observer whose observations stay missing
    for ``silent_windows`` windows is reported as a link fault.
    A reported H_i off the ground's recomputation from the observer's own observations by more
    than ``integrity_tol`` (relative) for ``checks_persistence`` windows is a data-integrity
    fault (judged while the ground holds all but ``integrity_max_loss`` of every observer's
    observations), and more of its observations lost (sequence gaps) than the links' nominal
    ``comms.packet_loss`` plus ``loss_tol`` (and the window's sampling spread) for
    ``checks_persistence`` windows a link fault.  A window is evaluated ``latency_s`` after it
    closes (its last images must have arrived).  A declared performance fault is identified
    (ground/fdir/identify.py), on its window or a later one of the episode,
    against the nominal bounds ``beta_tol`` (camera health located from the images),
    ``position_tol_m`` (camera from the images vs nav, nav vs plan), ``pointing_tol_deg``
    (reported pointing error), ``overlap_tol`` (seen vs expected POIs), ``explained_min``
    (share of the ΔH gap the reported pose must explain) and ``dv_rate_tol_mps2`` (Δv the
    observer commands while holding its PRO, per second)."""

    threshold: Literal["hardware", "sampled"] = Field(
        default="hardware",
        description="the threshold that decides: the quantile of the hardware's nominal ratio "
                    "distribution, or Eq. 11-12's ε-sampling (both are computed and archived)")
    false_alarms_per_observer_hour: float = Field(
        default=0.01, gt=0.0, le=100.0,
        description="false-alarm budget of the hardware threshold, per observer-hour")
    track_sigma_m: float = Field(default=0.05, gt=0.0,
                                 description="station-keeping accuracy on a PRO, 1σ per axis, m")
    transfer_sigma_m: float = Field(default=0.15, gt=0.0,
                                    description="tracking accuracy on a transfer, 1σ per axis, m")
    pointing_jitter_deg: float = Field(default=0.03, gt=0.0, lt=45.0,
                                       description="attitude loop tracking error, 1σ per axis")
    model_samples: int = Field(default=16, ge=2, le=1000,
                               description="pose draws of the hardware threshold per window")
    fuse_guidance: bool = Field(
        default=True, description="the detector also fails a window on its nav-vs-plan, "
                                  "pointing and Δv-rate tests (ground/fdir/consistency.py)")
    fuse_nis: bool = Field(
        default=True, description="the detector also fails a window when the Σ NIS of the "
                                  "observer's nav updates in it exceeds its χ² quantile at the "
                                  "window's false-alarm probability (the budget is split "
                                  "between this and the information test)")
    samples: int = Field(default=10, ge=1, le=1000)
    eps_deg: float = Field(default=1.0, gt=0.0, lt=45.0)
    floor: float = Field(default=0.002, ge=0.0,
                         description="guard under the selected threshold")
    persistence: int = Field(default=1, ge=1)
    persistence_window: int | None = Field(
        default=None, ge=1,
        description="main detector: declare on ``persistence`` exceedances among the last this "
                    "many windows (None: ``persistence`` in a row); the campaign report "
                    "re-scores its runs under such rules")
    checks_persistence: int = Field(
        default=2, ge=1, description="failed windows in a row that declare a data-integrity or "
                                     "packet-loss link fault")
    silent_windows: int = Field(default=2, ge=1)
    latency_s: float = Field(default=3.0, ge=0.0)
    settle_s: float = Field(default=30.0, ge=0.0,
                            description="images this soon after a slew are not judged")
    recovery: bool = Field(default=True, description="replan on an identified camera or "
                                                     "actuator fault "
                                                     "(ground/planning/mission_plan.py)")
    integrity_tol: float = Field(
        default=0.2, gt=0.0,
        description="relative difference between a reported H_i and the ground's recomputation "
                    "beyond which the report is inconsistent (data integrity)")
    integrity_max_loss: float = Field(
        default=0.1, ge=0.0, le=1.0,
        description="largest share of any observer's observations the ground may have lost for "
                    "a reported H_i to be judged (data integrity)")
    loss_tol: float = Field(default=0.2, gt=0.0, le=1.0,
                            description="share of a window's observations lost beyond the "
                                        "nominal comms.packet_loss")
    beta_tol: float = Field(default=0.1, gt=0.0, lt=1.0)
    position_tol_m: float = Field(default=0.5, gt=0.0)
    pointing_tol_deg: float = Field(default=1.0, gt=0.0)
    overlap_tol: float = Field(default=0.8, gt=0.0, le=1.0)
    explained_min: float = Field(default=0.5, gt=0.0, le=1.0)
    dv_rate_tol_mps2: float = Field(
        default=5e-4, gt=0.0,
        description="commanded Δv per second while holding a PRO (natural motion, nominally "
                    "~1e-5) above which the observer fights a force it does not model: an orbit "
                    "actuator fault (a 3 m nav bias step costs ~2.6e-4 in its window, a thruster "
                    "leak of 20% of the maximum thrust ~8.6e-4), m/s²")
    nis_alpha: float = Field(default=1e-3, gt=0.0, lt=1.0,
                             description="baseline chi2_nis: false-alarm probability per window")
    cusum_drift: float = Field(default=0.02, ge=0.0,
                               description="baseline cusum: allowed |1 - ΔH_i/ΔH_i^pred| "
                                           "per window")
    cusum_threshold: float = Field(default=0.15, gt=0.0, description="baseline cusum: alarm level")
    fixed_threshold: float = Field(default=0.1, gt=0.0,
                                   description="baseline fixed_threshold: H_m,i alarm level")

    @model_validator(mode="after")
    def _window(self) -> FdirSettings:
        if self.persistence_window is not None and self.persistence_window < self.persistence:
            raise ValueError(f"persistence_window ({self.persistence_window}) must be at least "
                             f"persistence ({self.persistence})")
        return self


class SimSettings(_Section):
    lockstep_timeout_s: float = Field(
        default=60.0, gt=0.0,
        description="per-tick answer timeout, s (wall): a participant alive but slow (a kernel "
                    "compiled on first use, a loaded machine) is waited for, so results stay "
                    "deterministic; a dead or stalled one is dropped as soon as the network "
                    "notices (at once, or after the 10 s Zenoh lease)")
    startup_timeout_s: float = Field(default=60.0, gt=0.0)
    substeps: int = Field(default=1, ge=1, description="RK4 steps per tick")
    cycle_budget_scale: float = Field(
        default=1.0, gt=0.0,
        description="a rate group overruns when its wall time exceeds its period times this",
    )


class Fault(_Section):
    spacecraft: int = Field(ge=0, description="the faulty observer; 0 for a common-mode kind")
    kind: FaultKind
    start_s: float = Field(ge=0.0)
    end_s: float | None = None
    magnitude: float | None = None

    @model_validator(mode="after")
    def _magnitude(self) -> Fault:
        if self.end_s is not None and self.end_s <= self.start_s:
            raise ValueError("fault end_s must be after start_s")
        if (self.spacecraft == 0) != (self.kind in COMMON_MODE_KINDS):
            raise ValueError(f"fault kind {self.kind!r} acts on "
                             + ("every observer: give spacecraft = 0"
                                if self.kind in COMMON_MODE_KINDS else "one observer (>= 1)"))
        if self.kind == "link_loss":
            return self
        if self.magnitude is None:
            raise ValueError(f"fault kind {self.kind!r} needs a magnitude")
        if (self.kind in ("camera_degradation", "packet_loss", "camera_calibration")
                and not 0.0 < self.magnitude < 1.0):
            raise ValueError(f"{self.kind} magnitude must be in (0, 1), got {self.magnitude}")
        return self


class Scenario(_Section):
    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$")
    seed: int = Field(default=0, ge=0)
    duration_s: float = Field(gt=0.0)
    orbit: Orbit = Orbit()
    target: Target = Target()
    camera: CameraSettings = CameraSettings()
    rates: Rates = Rates()
    comms: Comms = Comms()
    observers: Observers = Observers()
    sensors: Sensors = Sensors()
    nav: Nav = Nav()
    actuators: Actuators = Actuators()
    guidance: Guidance = Guidance()
    attitude: Attitude = Attitude()
    phases: list[Phase] = Field(default_factory=list)
    assignment: AssignmentSettings = AssignmentSettings()
    fdir: FdirSettings = FdirSettings()
    sim: SimSettings = SimSettings()
    faults: list[Fault] = Field(default_factory=list)

    @model_validator(mode="after")
    def _consistency(self) -> Scenario:
        n = self.observers.count
        for f in self.faults:
            if f.spacecraft > n:
                raise ValueError(f"fault on spacecraft {f.spacecraft} but observers.count = {n}")
        for where, formation in [("observers", self.observers)] + [
                (f"phase {p.name!r}", p) for p in self.phases]:
            for o in formation.overrides:
                if o.spacecraft > n:
                    raise ValueError(f"{where}: override of spacecraft {o.spacecraft} but "
                                     f"observers.count = {n}")
        starts = [p.start_s for p in self.phases]
        if starts != sorted(starts) or len(set(starts)) != len(starts):
            raise ValueError("phases must have strictly increasing start_s")
        ratio = self.rates.high_hz / self.sensors.star_tracker_hz
        if abs(ratio - round(ratio)) > 1e-9 or ratio < 1.0 - 1e-9:
            raise ValueError(f"sensors.star_tracker_hz = {self.sensors.star_tracker_hz} must "
                             f"divide rates.high_hz = {self.rates.high_hz}")
        for c in self.comms.cuts:
            for end in (c.a, c.b):
                if end.startswith("sc") and int(end[2:]) > n:
                    raise ValueError(f"link cut names {end} but observers.count = {n}")
        return self

    @property
    def n_ticks(self) -> int:
        """Number of high-rate ticks in the run (t = 0 .. duration_s)."""
        return int(math.floor(self.duration_s * self.rates.high_hz + 1e-9)) + 1

    def with_overrides(self, seed: int | None = None, duration_s: float | None = None) -> Scenario:
        """A copy with the command-line overrides applied (and validated)."""
        data = self.model_dump()
        if seed is not None:
            data["seed"] = seed
        if duration_s is not None:
            data["duration_s"] = duration_s
        return Scenario.model_validate(data)


class ScenarioError(ValueError):
    """A scenario file that cannot be read or does not validate; the message names the field."""


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file (or, with a ``.json`` suffix, a resolved scenario
    as written by campaigns); raise ScenarioError with a readable message."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as e:
        raise ScenarioError(f"cannot read scenario {p}: {e.strerror}") from e
    if p.suffix == ".json":
        try:
            return Scenario.model_validate_json(text)
        except ValidationError as e:
            raise ScenarioError(f"{p}: invalid scenario: {e}") from None
    return parse_scenario(text, source=str(p))


def parse_scenario(text: str, source: str = "<string>") -> Scenario:
    """Validate scenario TOML text (see load_scenario)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{source}: not valid TOML: {e}") from e
    try:
        return Scenario.model_validate(data)
    except ValidationError as e:
        lines = [f"{source}: invalid scenario:"]
        for err in e.errors():
            where = ".".join(str(x) for x in err["loc"]) or "(top level)"
            lines.append(f"  {where}: {err['msg']}")
        raise ScenarioError("\n".join(lines)) from None
