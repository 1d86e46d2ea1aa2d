"""Navigation app: relative-state Kalman filter on the HCW model.

Rate group mid (ω_mid).  Input: the relative navigation sensor (LVLH position and velocity).
Output: the state estimate [x y z vx vy vz] (m, m/s, LVLH) with its covariance and NIS.
The model is the flight model (HCW, exact discretization Φ = expm(A·dt)), not the truth.
"""

from __future__ import annotations

import numpy as np

from fsw.lib import hcw, kalman
from interfaces import topics
from interfaces.app import App, AppContext, Input, Output
from interfaces.messages import RelNavMeasurement, StateEstimate


class NavApp(App):
    NAME = "nav"
    RATE = "mid"
    INPUTS = (
        Input(lambda c: topics.relnav(c.mission, c.spacecraft or 0), RelNavMeasurement, "on_relnav"),
    )
    OUTPUTS = (
        Output("estimate", lambda c: topics.key(c.mission, c.node, "nav", "estimate"), StateEstimate),
    )

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.n = hcw.mean_motion(sc.orbit.altitude_km * 1e3)
        self.q = sc.nav.q_accel_m2_s3
        self.x: np.ndarray | None = None
        self.P = np.eye(6)
        self.t_est = 0.0
        self.nis: float | None = None
        self._meas: RelNavMeasurement | None = None
        self._models: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def on_relnav(self, msg: RelNavMeasurement) -> None:
        self._meas = msg

    def step(self, t: float) -> None:
        meas, self._meas = self._meas, None
        if self.x is None:
            if meas is None:
                return
            # First fix: the measurement itself, with the sensor's covariance.
            self.x, self.P, self.t_est = np.array(meas.r_m + meas.v_mps), _R(meas), meas.t_sim
        else:
            self._propagate_to(meas.t_sim if meas is not None else t)
            if meas is not None:
                self.x, self.P, self.nis = kalman.update(
                    self.x, self.P, np.array(meas.r_m + meas.v_mps), np.eye(6), _R(meas))
        self._propagate_to(t)
        self.publish("estimate", StateEstimate(
            sender=self.ctx.node, t_sim=t, spacecraft=self.ctx.spacecraft or 0,
            x=self.x.tolist(), P=self.P.tolist(), nis=self.nis))

    def _propagate_to(self, t: float) -> None:
        dt = round(t - self.t_est, 9)
        if dt <= 0.0 or self.x is None:
            return
        Ad, Qd = self._model(dt)
        self.x, self.P = kalman.predict(self.x, self.P, Ad, Qd)
        self.t_est = t

    def _model(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(Φ, Qd) for step dt, cached: the rate group makes dt constant."""
        m = self._models.get(dt)
        if m is None:
            m = (hcw.hcw_stm(self.n, dt), hcw.process_noise(self.n, dt, self.q))
            self._models[dt] = m
        return m


def _R(meas: RelNavMeasurement) -> np.ndarray:
    """Measurement covariance of the relative navigation sensor (6x6, m², m²/s²)."""
    return np.diag([meas.sigma_r_m**2] * 3 + [meas.sigma_v_mps**2] * 3)
