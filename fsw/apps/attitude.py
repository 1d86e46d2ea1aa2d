"""Attitude app: attitude determination and pointing control (paper Sec. II.B).

Rate group high (ω_high).  Inputs: the attitude sensors (gyro every tick, star tracker when it
has a fix), the nav state estimate (own position) and the camera's pointing target (until a
camera app publishes one: the target's centre, the LVLH origin).  Outputs: the reaction-wheel
torque command every tick and the attitude estimate/status at ω_mid.

The 10 Hz chain runs on the compiled kernels of ``fsw.lib.attitude_kernels`` (the same
mathematics as ``fsw.lib.mekf``, ``fsw.lib.attitude.repoint`` and
``fsw.lib.attitude_control.tracking_torque``, which stay the tested reference).

Each cycle: the MEKF (``fsw.lib.mekf``) propagates with the gyro and updates with the star
tracker; the desired attitude puts the camera boresight on the line of sight to the pointing
target (LVLH, carried into ECI by the onboard LVLH model ``gnc.frames``) by the shortest
rotation from the previous desired attitude (``fsw.lib.attitude.repoint``: roll-free pointing,
no singular line of sight).  An error larger than ``attitude.slew_threshold_deg`` starts a slew
planned by SCP with the rate limit (``scp_slew``; slerp if SCP fails); otherwise the nonlinear
tracking law (``fsw.lib.attitude_control``) follows the pointing attitude directly.  Before the
estimator has its first star-tracker fix the app damps the body rate with the gyro.

The wheel momentum is not measured; the app integrates its own commands (h' = −τ) from the
initial zero momentum, which the gyroscopic compensation uses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from fsw.lib import attitude_kernels as kern
from fsw.lib import attitude_rows, mekf
from fsw.lib.attitude import AttitudePlan, repoint, scp_slew, slerp_plan
from fsw.lib.attitude_control import gains_for
from gnc import quat
from gnc.frames import lvlh_to_eci_quat
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    AttitudeEstimate,
    AttitudeMeasurement,
    PointingTarget,
    StateEstimate,
    WheelCommand,
)
from interfaces.contracts.timing import TIME_TOL_S
from interfaces.runtime.app import App, AppContext, Input, Output
from interfaces.runtime.rows import Row, joined

DESIRED_RATE_STEP_S = 1.0
"""Finite-difference step for the desired angular velocity, s."""


class AttitudeApp(App):
    NAME = "attitude"
    RATE = "high"
    INPUTS = (
        Input(cat.ATTITUDE_SENSORS, "on_sensors"),
        Input(cat.NAV_ESTIMATE, "on_estimate"),
        Input(cat.POINTING, "on_target"),
    )
    OUTPUTS = (Output("wheels", cat.WHEELS), Output("estimate", cat.ATTITUDE_ESTIMATE))
    CRITICAL = ("q", "b", "P", "nis", "h_wheels", "tau", "w_est", "target", "target_rate",
                "target_accel", "target_t", "slew", "slew_t0", "slew_end", "q_point", "mode",
                "_meas", "t_att", "_est", "_x_est", "t_star")
    REBUILT = ("rows", "row", "_slew")
    """The fleet's block and this app's row in it (its learnt fields are ``CRITICAL`` above,
    each a ``Row``: ``attitude_rows.STATE``; the rest is rebuilt: the plan's nodes from
    ``slew``, each cycle's staged inputs, the constants), and the plan behind ``slew``."""

    # the hot state, in this app's row of the fleet's block (``fsw.lib.attitude_rows``)
    q = Row("q")
    """the MEKF attitude R_eci_body (scalar last); None before the first star-tracker fix"""
    b, P, nis = Row("b"), Row("P"), Row("nis")
    h_wheels, tau, w_est = Row("h_wheels"), Row("tau"), Row("w_est")
    target = Row("target")
    """the pointing target (LVLH, m) at ``target_t``"""
    target_rate, target_accel = Row("target_rate"), Row("target_accel")
    """its motion (LVLH, m/s, m/s²)"""
    target_t, slew_t0, slew_end = Row("target_t"), Row("slew_t0"), Row("slew_end")
    q_point = Row("q_point")
    """the last desired attitude (quaternion) while tracking"""
    t_att, t_star = Row("t_att"), Row("t_star")
    """the time of the MEKF state and of the last star-tracker attitude, s"""
    _x_est = Row("x_est")
    """the nav estimate as an array (LVLH, m, m/s)"""

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.rows, self.row = attitude_rows.new_rows(), 0  # alone: a block of one row
        self.sc_id = ctx.spacecraft or 0
        self.n = ctx.constants.n_rad_s
        self.orbit = (math.radians(sc.orbit.inclination_deg), math.radians(sc.orbit.raan_deg),
                      math.radians(sc.orbit.arg_latitude_deg))
        """the target's orbit as the LVLH model flies it: inclination, node, argument of
        latitude at t = 0 (rad; ``gnc.frames.lvlh_to_eci_quat``)"""
        self.dt = sc.rates.dt_s
        self.mid_every = sc.rates.ticks_per("mid")
        self.J = np.diag(sc.observers.inertia_kg_m2)
        self.cfg = sc.attitude
        self.boresight = np.array(sc.attitude.boresight_body, dtype=float)
        self.st_axis = int(np.argmax(np.abs(self.boresight)))  # star tracker co-aligned
        self.w_max = math.radians(sc.attitude.slew_rate_max_dps)
        self.gains = gains_for(sc.attitude.settling_time_s, w_max_radps=self.w_max)
        self._w_limit = -1.0 if self.gains.w_max_radps is None else self.gains.w_max_radps
        self._slew_threshold_rad = math.radians(sc.attitude.slew_threshold_deg)
        self.tau_max = sc.actuators.wheel_max_torque_nm
        s = sc.sensors
        self.sigma_v, self.sigma_u = s.gyro_arw_rad_rts, s.gyro_bias_rw_rad_s15
        self.bias_sigma0 = s.gyro_bias_sigma_radps
        self._constants()
        self._slew: AttitudePlan | None = None
        self.mode = "init"
        self._meas: list[AttitudeMeasurement] = []
        self._est: StateEstimate | None = None
        self._failure: Exception | None = None
        """an error of this cycle's publications when stepped with the fleet (``step_all``)"""

    def _constants(self) -> None:
        """This app's constants in its row (``attitude_rows.CONSTANTS``)."""
        d, i = self.rows.data, self.row
        d["J"][i], d["boresight"][i] = self.J, self.boresight
        d["const"][i] = (self.gains.kp, self.gains.kd, self._w_limit, self.tau_max,
                         self._slew_threshold_rad, self.sigma_v, self.sigma_u, self.n,
                         *self.orbit)

    @property
    def slew(self) -> AttitudePlan | None:
        """The slew plan in force (its nodes also in this app's row)."""
        return self._slew

    @slew.setter
    def slew(self, plan: AttitudePlan | None) -> None:
        self._slew = plan
        attitude_rows.set_slew(self.rows, self.row, None if plan is None else plan.nodes())

    def on_sensors(self, msg: AttitudeMeasurement) -> None:
        self._meas.append(msg)

    def on_estimate(self, msg: StateEstimate) -> None:
        self._est = msg
        self._x_est = msg.x

    def on_target(self, msg: PointingTarget) -> None:
        self.target = msg.target_lvlh_m
        self.target_rate = msg.target_rate_lvlh_mps
        self.target_accel = msg.target_accel_lvlh_mps2
        self.target_t = msg.t_sim

    def _target_at(self, t: float) -> np.ndarray:
        """The pointing target extrapolated to time t (LVLH, m), to second order."""
        dt = t - self.target_t
        return self.target + (self.target_rate + 0.5 * dt * self.target_accel) * dt

    # --- cycle ---------------------------------------------------------------------------------

    def step(self, t: float) -> None:
        if self._failure is not None:  # its cycle was stepped with its fleet's, then failed
            failure, self._failure = self._failure, None
            raise failure
        pending, self._meas = sorted(self._meas, key=lambda m: m.t_sim), []
        meas = pending[-1] if pending else None
        self.tau = np.zeros(3)
        try:
            for m in pending:
                self._determine(m)
            if self.q is None or self._est is None:
                w = np.array(meas.gyro_radps) if meas is not None else np.zeros(3)
                self.tau = _saturate(-self.J @ (self.gains.kd * w), self.tau_max)  # rate damping
            else:
                self.tau = self._control(t)
        finally:  # safe mode on any failure: zero torque is still commanded, then the error
            self.h_wheels -= self.tau * self.dt  # propagates to the executive's counter
            self._command(t)
        self._report_due(t)

    @classmethod
    def step_all(cls, apps: Sequence[AttitudeApp], t: float) -> Sequence[AttitudeApp]:
        """The cycle at ``t`` (s) of a fleet's attitude apps together: their rows stepped by
        one compiled call (``fsw.lib.attitude_rows.step_rows``, the bits of :meth:`step`),
        then each app's command and report published on its own bus.  An app whose row the
        compiled cycle cannot take (no star-tracker fix yet, no nav estimate, not exactly one
        measurement pending) or leaves (a slew to plan, no line of sight, a torque not
        finite) is returned, untouched, to step alone."""
        rows = joined(apps)
        ready = [app._stage(t) for app in apps]
        first = apps[0]
        status = attitude_rows.step_rows(rows, np.flatnonzero(ready), t, first.dt,
                                         DESIRED_RATE_STEP_S, first._reports(t))
        left: list[AttitudeApp] = []
        for app, done in zip(apps, status.tolist(), strict=True):
            if done not in attitude_rows.DONE:
                left.append(app)
                continue
            app._meas = []
            if done == attitude_rows.TRACKED:
                app.mode = "track"
            try:
                app._command(t)
                app._report_due(t)
            except Exception as exc:  # noqa: BLE001 - its own failure: raised by its own step
                app._failure = exc
                left.append(app)
        return left

    def _stage(self, t: float) -> bool:
        """This cycle's inputs in the app's row (the pending measurement, the nav estimate's
        time, whether a slew plan is followed), if the compiled cycle can take it."""
        if len(self._meas) != 1 or self._est is None or self.t_att is None:
            return False
        m, d, i = self._meas[0], self.rows.data, self.row
        d["t_meas"][i], d["gyro"][i], d["t_est"][i] = m.t_sim, m.gyro_radps, self._est.t_sim
        d["star_on"][i] = m.star_tracker is not None
        if m.star_tracker is not None:
            d["star"][i] = m.star_tracker
            d["r_diag"][i] = m.st_sigma_cross_rad**2
            d["r_diag"][i, self.st_axis] = m.st_sigma_roll_rad**2
        d["slewing"][i] = (self.mode == "slew" and self._slew is not None
                           and t - self.slew_t0 <= self.slew_end)
        return True

    def _command(self, t: float) -> None:
        """Publish this cycle's wheel torque."""
        self.publish("wheels", WheelCommand(sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id,
                                            torque_body_nm=self.tau.tolist()))

    def _report_due(self, t: float) -> None:
        """The attitude estimate, at ω_mid once the MEKF is initialised."""
        if self._reports(t) and self.q is not None:
            self._report(t)

    def _reports(self, t: float) -> bool:
        """Whether the cycle at ``t`` (s) reports the estimate (at ω_mid)."""
        return round(t / self.dt) % self.mid_every == 0

    def _determine(self, meas: AttitudeMeasurement) -> None:
        """MEKF: propagate with the gyro to the sample's time, update with the star tracker
        (initialise on its first fix).  The gyro sample is the mean rate over the tick before
        it; after a lost sample that rate is used over the whole gap (no rotation is lost)."""
        w_meas = np.array(meas.gyro_radps)
        dt = meas.t_sim - self.t_att if self.t_att is not None else 0.0
        if self.q is not None and dt > TIME_TOL_S:
            self.q, self.b, self.P = kern.mekf_propagate(self.q, self.b, self.P, w_meas, dt,
                                                         self.sigma_v, self.sigma_u)
        if meas.star_tracker is not None:
            self.t_star = meas.t_sim
            R = np.diag(np.full(3, meas.st_sigma_cross_rad**2))
            R[self.st_axis, self.st_axis] = meas.st_sigma_roll_rad**2
            if self.q is None:
                self.q, self.b, self.P = mekf.mekf_init(np.array(meas.star_tracker), R,
                                                        self.bias_sigma0)
            else:
                self.q, self.b, self.P, self.nis = kern.mekf_update(
                    self.q, self.b, self.P, np.array(meas.star_tracker), R)
        if self.q is not None:
            self.t_att = meas.t_sim
        self.w_est = w_meas - self.b

    def _los_eci(self, t: float) -> np.ndarray:
        """Line of sight to the pointing target at time t, ECI axes (m), from the nav estimate
        and the target, each extrapolated with its velocity."""
        assert self._est is not None
        los = kern.los_eci(t, self.n, *self.orbit, self._x_est, self._est.t_sim, self.target,
                           self.target_rate, self.target_accel, self.target_t)
        n2 = float(los @ los)
        if not (n2 > 0.0 and math.isfinite(n2)):
            raise ValueError(f"no line of sight to the pointing target at t={t:.1f} s "
                             f"(target on the spacecraft, or non-finite)")
        return los

    def _control(self, t: float) -> np.ndarray:
        """Wheel torque tracking the slew plan, or the pointing attitude (quaternions R_eci_body,
        scalar last: no scipy Rotation on the 10 Hz path; the tracking cycle is one compiled
        call, :func:`fsw.lib.attitude_kernels.track_cycle`)."""
        assert self.q is not None and self._est is not None
        if self.mode == "slew" and self.slew is not None and t - self.slew_t0 <= self.slew_end:
            r_des, w_des, wdot_des = self.slew.at_quat(t - self.slew_t0)
        else:
            status, t_bad, q_des, angle, tau = kern.track_cycle(
                t, DESIRED_RATE_STEP_S, self.n, *self.orbit, self._x_est, self._est.t_sim,
                self.target, self.target_rate, self.target_accel, self.target_t,
                self.q if self.q_point is None else self.q_point, self.q, self.w_est,
                self.boresight, self.J, self.h_wheels, self.gains.kp, self.gains.kd,
                self._w_limit, self.tau_max, self._slew_threshold_rad)
            if status == kern.NO_LINE_OF_SIGHT:
                raise ValueError(f"no line of sight to the pointing target at t={t_bad:.1f} s "
                                 f"(target on the spacecraft, or non-finite)")
            if status == kern.TRACKED:
                self.mode, self.q_point = "track", q_des
                return _finite(tau)
            self._plan_slew(t, angle)
            self.q_point = None
            r_des, w_des, wdot_des = self.slew.at_quat(0.0)  # type: ignore[union-attr]
        tau, _ = kern.tracking_torque(self.q, self.w_est, r_des, w_des, wdot_des, self.J,
                                      self.h_wheels, self.gains.kp, self.gains.kd,
                                      self._w_limit, self.tau_max)
        return _finite(tau)

    def _plan_slew(self, t: float, angle: float) -> None:
        """Plan a rate-limited slew (SCP, slerp as fallback) onto the pointing attitude."""
        assert self.q is not None
        r_est = Rotation.from_quat(self.q)
        duration = max(10.0, 1.5 * angle / self.w_max + self.cfg.settling_time_s)
        r_end = repoint(r_est, self._los_eci(t + duration), self.boresight)
        nodes = max(8, int(math.ceil(duration / 5.0)))
        plan = scp_slew(r_est, r_end, duration, nodes, self.w_max, w0=self.w_est)
        if not plan.converged:
            self.log.warning("slew SCP %s; using slerp", plan.status)
            plan = slerp_plan(r_est, r_end, 0.0, duration)
        self.slew, self.slew_t0, self.slew_end, self.mode = plan, t, duration, "slew"
        self.log.info("slew of %.1f° planned over %.0f s", math.degrees(angle), duration)

    def _report(self, t: float) -> None:
        assert self.q is not None
        q_lvlh = quat.mul(quat.conj(lvlh_to_eci_quat(t, self.n, *self.orbit)), self.q)
        error = 0.0
        if self._est is not None:
            los = self._los_eci(t)
            b = quat.rotate(self.q, self.boresight)
            error = math.acos(min(1.0, max(-1.0, float(b @ los)
                                                 / max(1e-12, float(np.linalg.norm(los))))))
        self.publish("estimate", AttitudeEstimate(
            sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id, q_eci_body=self.q.tolist(),
            q_lvlh_body=q_lvlh.tolist(), gyro_bias_radps=self.b.tolist(),
            sigma_att_rad=float(math.sqrt(max(0.0, np.trace(self.P[:3, :3])))),
            target_lvlh_m=self._target_at(t).tolist(), pointing_error_rad=error,
            mode=self.mode, torque_body_nm=self.tau.tolist(), nis=self.nis,  # type: ignore[arg-type]
            wheel_momentum_nms=self.h_wheels.tolist(),
            star_tracker_age_s=None if self.t_star is None else max(0.0, t - self.t_star)))


def _finite(tau: np.ndarray) -> np.ndarray:
    """The torque command, or the error that sends the app to safe mode (zero torque)."""
    if not np.isfinite(tau).all():
        raise ValueError(f"non-finite torque command {tau.tolist()} (safe mode: zero torque)")
    return tau


def _saturate(tau: np.ndarray, tau_max: float) -> np.ndarray:
    """Scale a torque so that no axis exceeds ``tau_max``, keeping its direction."""
    m = float(np.abs(tau).max())
    return tau if m <= tau_max else tau * (tau_max / m)
