"""The flight side's settings: actuators, guidance, attitude, sensors and nav (``fsw/``, and
the sim's units that stand in for the hardware)."""

from __future__ import annotations

from pydantic import Field, model_validator

from interfaces.contracts.scenario.base import Section


class Actuators(Section):
    """Thrusters (body-fixed, ± each body axis) and three reaction wheels along the body axes."""

    thruster_max_force_n: float = Field(default=0.02, gt=0.0, description="per axis, N")
    thruster_min_impulse_ns: float = Field(default=1e-4, ge=0.0, description="minimum impulse bit")
    thruster_noise_frac: float = Field(default=0.01, ge=0.0, lt=1.0, description="1σ, of force")
    wheel_max_torque_nm: float = Field(default=2e-3, gt=0.0, description="per wheel, N·m")
    wheel_max_momentum_nms: float = Field(default=0.02, gt=0.0, description="per wheel, N·m·s")


class Guidance(Section):
    """Orbit guidance: SCP transfers (L1 fuel, keep-out sphere) tracked by MPC at ω_low."""

    keep_out_m: float = Field(default=8.0, gt=0.0, description="keep-out sphere radius d_min, m")
    node_spacing_s: float = Field(default=20.0, gt=0.0, description="SCP interval, s")
    mpc_horizon: int = Field(default=20, ge=2, le=200, description="MPC steps of 1/ω_low")
    plan_thrust_fraction: float = Field(
        default=0.5, gt=0.0, le=1.0,
        description="fraction of the thrust limit the plan may use (the rest is MPC margin)")


class Attitude(Section):
    """Attitude guidance and control (ω_high): slews planned by SCP, nonlinear tracking."""

    settling_time_s: float = Field(default=30.0, ge=1.0, le=3600.0,
                                   description="attitude loop settling time, s (1 to 3,600)")
    slew_rate_max_dps: float = Field(default=2.0, gt=0.0, le=30.0,
                                     description="slew rate limit, deg/s (at most 30)")
    slew_threshold_deg: float = Field(default=10.0, gt=0.0, le=180.0,
                                      description="errors above this are slewed on a plan")
    boresight_body: tuple[float, float, float] = (0.0, 0.0, 1.0)

    @model_validator(mode="after")
    def _boresight(self) -> Attitude:
        if max(abs(c) for c in self.boresight_body) == 0.0:
            raise ValueError("attitude.boresight_body must be a non-zero vector")
        return self


STAR_TRACKER_MIN_ARCSEC = 0.1
"""The finest star tracker noise a scenario may declare (1σ, arcsec): the best trackers flown
are near 1 arcsec.  Far below it the attitude filter's covariance, its variance next to the
gyro's, is no longer positive definite in floating point (8.8e-206 arcsec stopped the
attitude app)."""


class Sensors(Section):
    relnav_sigma_r_m: float = Field(default=0.1, gt=0.0, le=100.0,
                                    description="1σ position noise, m (at most 100)")
    relnav_sigma_v_mps: float = Field(default=0.002, gt=0.0, le=10.0,
                                      description="1σ velocity noise, m/s (at most 10: a draw "
                                                  "stays within the measurement's 1,000 m/s)")
    gyro_arw_rad_rts: float = Field(default=4.4e-5, ge=0.0, le=0.01,
                                    description="angle random walk σv, rad/√s (0.15°/√h; at "
                                                "most 0.01)")
    gyro_bias_rw_rad_s15: float = Field(default=3e-7, ge=0.0, le=1e-3,
                                        description="bias random walk σu, rad/s^1.5 (at most "
                                                    "1e-3)")
    gyro_bias_sigma_radps: float = Field(default=1e-4, gt=0.0, le=0.1,
                                         description="1σ initial gyro bias, rad/s (at most 0.1)")
    star_tracker_hz: float = Field(default=1.0, gt=0.0)
    star_tracker_cross_arcsec: float = Field(
        default=10.0, ge=STAR_TRACKER_MIN_ARCSEC, le=3600.0,
        description="1σ, at least 0.1 arcsec, at most 1°")
    star_tracker_roll_arcsec: float = Field(
        default=60.0, ge=STAR_TRACKER_MIN_ARCSEC, le=3600.0,
        description="1σ, about boresight, at least 0.1 arcsec, at most 1°")


class Nav(Section):
    q_accel_m2_s3: float = Field(
        default=1e-12, gt=0.0, description="spectral density of unmodelled acceleration, m²/s³"
    )
