"""Navigation app: relative-state Kalman filter on the HCW model.

Rate group mid (ω_mid).  Inputs: the relative navigation sensor (LVLH position and velocity)
and the guidance status, whose commanded LVLH acceleration (held for one ω_low period) enters
the prediction as a known input.  Output: the state estimate [x y z vx vy vz] (m, m/s, LVLH)
with its covariance and NIS.  The model is the flight model (HCW, exact ZOH discretization
expm([[A, B], [0, 0]]·dt)), not the truth.  A commanded acceleration u adds process noise for its
execution error: one error of 1σ ``THRUST_ERROR_FRAC·|u|`` (m/s², thruster noise and thrust
direction error) held over the command period T acts like white acceleration noise of density
``(THRUST_ERROR_FRAC·|u|)²·T`` (m²/s³).

A filter that diverges anyway (a state or variance beyond what its message may carry,
``interfaces.contracts.messages``) restarts from its next measurement, counts it in
``StateEstimate.resets`` and publishes nothing until then.
"""

from __future__ import annotations

import numpy as np

from gnc import hcw, kalman
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    MAX_RANGE_M,
    MAX_SPEED_MPS,
    GuidanceStatus,
    OnboardCommand,
    RelNavMeasurement,
    StateEstimate,
)
from interfaces.contracts.timing import TIME_TOL_S
from interfaces.runtime.app import App, AppContext, Input, Output

THRUST_ERROR_FRAC = 0.05
"""1σ execution error of a commanded acceleration, as a fraction of it."""
STATE_BOUNDS = np.array([MAX_RANGE_M] * 3 + [MAX_SPEED_MPS] * 3)
"""What a StateEstimate may carry, per component (m, m/s)."""


class NavApp(App):
    NAME = "nav"
    RATE = "mid"
    INPUTS = (Input(cat.RELNAV, "on_relnav"), Input(cat.GUIDANCE_STATUS, "on_guidance"),
              Input(cat.FDIR_COMMAND, "on_command"))
    OUTPUTS = (Output("estimate", cat.NAV_ESTIMATE),)
    CRITICAL = ("x", "P", "t_est", "nis", "resets", "_cmd", "_meas", "_reset_asked")
    REBUILT = ("_models",)  # the discrete models by step, a cache

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.n = ctx.constants.n_rad_s
        self.q = sc.nav.q_accel_m2_s3
        self.x: np.ndarray | None = None
        self.P = np.eye(6)
        self.t_est = 0.0
        self.nis: float | None = None
        self.resets = 0
        self.cmd_period = 1.0 / sc.rates.low_hz
        self._cmd: tuple[float, np.ndarray] = (0.0, np.zeros(3))  # (start s, LVLH accel m/s²)
        self._meas: RelNavMeasurement | None = None
        self._reset_asked = False  # by the onboard FDIR (fsw/apps/fdir.py)
        self._models: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def on_relnav(self, msg: RelNavMeasurement) -> None:
        self._meas = msg

    def on_guidance(self, msg: GuidanceStatus) -> None:
        self._cmd = (msg.t_sim, np.array(msg.accel_lvlh_mps2))

    def on_command(self, msg: OnboardCommand) -> None:
        if msg.command == "nav_reset":
            self._reset_asked = True

    def _accel(self, t: float) -> np.ndarray:
        """The commanded acceleration acting from time t (zero outside its hold period)."""
        t0, u = self._cmd
        return u if t0 - TIME_TOL_S <= t < t0 + self.cmd_period - TIME_TOL_S else np.zeros(3)

    def step(self, t: float) -> None:
        if self._reset_asked:
            self._reset_asked = False
            self._restart(t, "reset by the onboard FDIR")
        meas, self._meas = self._meas, None
        if self.x is None:
            if meas is None:
                return
            # First fix: the measurement itself, with the sensor's covariance.
            self.x, self.P, self.t_est = np.array(meas.r_m + meas.v_mps), _R(meas), meas.t_sim
        else:
            self._propagate_to(meas.t_sim if meas is not None else t)
            self.nis = None  # only this step's update has one
            if meas is not None:
                self.x, self.P, self.nis = kalman.update(
                    self.x, self.P, np.array(meas.r_m + meas.v_mps), np.eye(6), _R(meas))
        self._propagate_to(t)
        if kalman.diverged(self.x, self.P, STATE_BOUNDS):
            self._restart(t, "diverged")
            return
        self.publish("estimate", StateEstimate(
            sender=self.ctx.node, t_sim=t, spacecraft=self.ctx.spacecraft or 0,
            x=self.x.tolist(), P=self.P.tolist(), nis=self.nis, resets=self.resets))

    def _restart(self, t: float, why: str) -> None:
        """Drop the estimate (diverged, or reset by command): the next measurement starts the
        filter again."""
        self.resets += 1
        self.log.warning("%s nav %s at t=%.1f s; restarting from the next measurement "
                         "(reset #%d)", self.ctx.node, why, t, self.resets)
        self.x, self.P, self.nis = None, np.eye(6), None

    def _propagate_to(self, t: float) -> None:
        dt = round(t - self.t_est, 9)
        if dt <= 0.0 or self.x is None:
            return
        Ad, Bd, Qd = self._model(dt)
        u = self._accel(self.t_est)
        q_thrust = (THRUST_ERROR_FRAC * float(np.linalg.norm(u)))**2 * self.cmd_period
        self.x, self.P = kalman.predict(self.x, self.P, Ad, Qd * (1.0 + q_thrust / self.q), Bd, u)
        self.t_est = t

    def _model(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Φ, Γ, Qd) for step dt (Qd for the base noise density), cached: the rate group makes
        dt constant."""
        m = self._models.get(dt)
        if m is None:
            m = (*hcw.discretize(self.n, dt), hcw.process_noise(self.n, dt, self.q))
            self._models[dt] = m
        return m


def _R(meas: RelNavMeasurement) -> np.ndarray:
    """Measurement covariance of the relative navigation sensor (6x6, m², m²/s²)."""
    return np.diag([meas.sigma_r_m**2] * 3 + [meas.sigma_v_mps**2] * 3)
