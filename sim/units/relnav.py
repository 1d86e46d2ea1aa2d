"""The relative-navigation sensors: each observer's noisy LVLH position and velocity relative to
the target (``sim/sensors.py``, ``RelNavSensor``), one ``RelNavMeasurement`` every ω_mid
period."""

from __future__ import annotations

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import RelNavMeasurement
from interfaces.contracts.rng import stream
from sim.sensors import RelNavSensor
from sim.units.unit import Sensed, Unit, UnitContext


class RelNav(Unit):
    NAME = "relnav"
    RATE = "mid"
    OUTPUTS = (cat.RELNAV,)

    def __init__(self, ctx: UnitContext) -> None:
        super().__init__(ctx)
        sc, sen = ctx.scenario, ctx.scenario.sensors
        self.sensors = [RelNavSensor(sen.relnav_sigma_r_m, sen.relnav_sigma_v_mps,
                                     stream(sc.seed, "relnav", i)) for i in self.ids]
        """one per observer (fault hook ``bias_m``: ``faults/hardware.py``)"""

    def step(self, now: Sensed) -> None:
        for i, (sc_id, sensor) in enumerate(zip(self.ids, self.sensors, strict=True)):
            r, v = sensor.measure(now.rel_lvlh[i, :3], now.rel_lvlh[i, 3:])
            self.publish(cat.RELNAV, i, RelNavMeasurement(
                sender=topics.SIM, t_sim=now.t_s, spacecraft=sc_id, r_m=r.tolist(),
                v_mps=v.tolist(), sigma_r_m=sensor.sigma_r_m, sigma_v_mps=sensor.sigma_v_mps))
