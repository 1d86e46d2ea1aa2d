"""The ground FDIR's settings (``ground/fdir/``, docs/fdir.md)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from interfaces.contracts.scenario.base import Section


class FdirSettings(Section):
    """The ground FDIR (ground/apps/fdir.py, docs/fdir.md): every
    FDI window (``rates.fdi_period_s``) each observer's information gain is compared with the
    nominal twin's prediction (Eq. 9).  The threshold in force (``threshold``) is by default
    the hardware model's (gnc/hardware_threshold.py): the quantile, for
    ``false_alarms_per_observer_hour``, of the ratio's distribution under no fault given the
    camera's noise (``[camera] noise_frac``), the station-keeping accuracy (``track_sigma_m``,
    ``transfer_sigma_m``) plus the nav's reported 1σ, and the pointing jitter
    (``pointing_jitter_deg``) plus the reported attitude knowledge and pointing error (up to
    ``pointing_tol_deg``), propagated through the twin with ``model_samples`` pose draws; or
    Eq. 11-12's (``samples`` pointings within ``eps_deg``).  Both are computed and archived
    every window; ``floor`` is a guard under the one in force.  With ``fuse_guidance`` a window
    also fails on the nav-vs-plan, pointing and Δv-rate tests (gnc/window_test.py:
    ``position_tol_m``, ``pointing_tol_deg``, ``dv_rate_tol_mps2``); with ``fuse_nis`` on the
    nav's normalized innovations.  A fault is declared after ``persistence`` failed windows in
    a row
    (or, with ``persistence_window`` = n, on the window that brings the failures among the last
    n decided windows to ``persistence``); the constellation's ratio (the global check, Eq. 6)
    declares a fault no single observer explains; an observer whose observations stay missing
    for ``silent_windows`` windows (one, when a healthy link could hardly empty a window) is
    reported as a link fault, as, with ground passes, one of which nothing came down early in
    a pass, or whose dump loses more than the link explains (ground/fdir/link_checks.py).
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
    detector: Literal["window", "sequential"] = Field(
        default="sequential",
        description="what declares an observer's information fault: the sequential test on "
                    "each image and nav update as they arrive (gnc/sequential_test.py, "
                    "gnc/image_scan.py) beside the window test, the budget split between them "
                    "(the default), or the window test alone (Eq. 9 per FDI window)")
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
                                  "pointing and Δv-rate tests (gnc/window_test.py)")
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
    silent_windows: int = Field(
        default=2, ge=1, description="silent windows in a row that declare a link fault when "
                                     "one alone does not (a link whose healthy bursts can "
                                     "empty a window)")
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
