"""The attitude sensors: each observer's gyro and star tracker (``sim/sensors.py``), one
``AttitudeMeasurement`` a tick.

Every tick the gyro gives the body rate averaged over the tick just flown; the star tracker,
co-aligned with the camera boresight, adds its R_eci_body quaternion on the ticks a fix is due
(``star_tracker_hz``) and its 1σ noise across and about the boresight.
"""

from __future__ import annotations

import math

import numpy as np

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import AttitudeMeasurement
from interfaces.contracts.rng import stream
from sim.sensors import Gyro, StarTracker
from sim.units.unit import Sensed, Unit, UnitContext

ARCSEC_RAD = math.pi / 180.0 / 3600.0


class AttitudeSensors(Unit):
    NAME = "attitude_sensors"
    RATE = "high"
    OUTPUTS = (cat.ATTITUDE_SENSORS,)

    def __init__(self, ctx: UnitContext) -> None:
        super().__init__(ctx)
        sc, sen = ctx.scenario, ctx.scenario.sensors
        self.dt_s = sc.rates.dt_s
        self.gyro = Gyro([stream(sc.seed, "gyro", i) for i in self.ids], sen.gyro_arw_rad_rts,
                         sen.gyro_bias_rw_rad_s15, sen.gyro_bias_sigma_radps)
        axis = int(np.argmax(np.abs(sc.attitude.boresight_body)))
        self.star_tracker = StarTracker([stream(sc.seed, "star_tracker", i) for i in self.ids],
                                        sen.star_tracker_cross_arcsec, sen.star_tracker_roll_arcsec,
                                        boresight_axis=axis, rate_hz=sen.star_tracker_hz)
        self.st_sigma_rad = (sen.star_tracker_cross_arcsec * ARCSEC_RAD,
                             sen.star_tracker_roll_arcsec * ARCSEC_RAD)
        """the star tracker's 1σ across and about the boresight, rad"""

    def measure(self, now: Sensed) -> tuple[np.ndarray, np.ndarray | None]:
        """Gyro rates (N, 3, rad/s) averaged over the last tick and star-tracker quaternions
        (N, 4) when a fix is due at ``now.t_s`` (else None)."""
        gyro = self.gyro.measure(now.attitude.mean_rate, self.dt_s)
        if not self.star_tracker.due(now.t_s):  # no Rotation built on the ticks without a fix
            return gyro, None
        return gyro, self.star_tracker.measure(now.t_s, now.attitude.r_eci_body())

    def step(self, now: Sensed) -> None:
        gyro, st = self.measure(now)
        cross, roll = self.st_sigma_rad
        for i, sc_id in enumerate(self.ids):
            self.publish(cat.ATTITUDE_SENSORS, i, AttitudeMeasurement(
                sender=topics.SIM, t_sim=now.t_s, spacecraft=sc_id, gyro_radps=gyro[i].tolist(),
                star_tracker=None if st is None else st[i].tolist(),
                st_sigma_cross_rad=cross, st_sigma_roll_rad=roll))
