"""The inspection cameras: each observer's image of the target's POIs (``sim/camera.py``), one
``CameraImage`` every ω_mid period, from the true pose and the camera's faults."""

from __future__ import annotations

import numpy as np

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import CameraImage
from interfaces.contracts.rng import stream
from sim.camera import TruthCameras
from sim.units.unit import Sensed, Unit, UnitContext


class Camera(Unit):
    NAME = "camera"
    RATE = "mid"
    OUTPUTS = (cat.CAMERA_IMAGE,)

    def __init__(self, ctx: UnitContext) -> None:
        super().__init__(ctx)
        sc, k = ctx.scenario, ctx.constants
        self.cameras = TruthCameras(
            k.poi_pos, k.poi_normal, k.camera, np.array(sc.attitude.boresight_body),
            sc.camera.noise_frac, [stream(sc.seed, "camera", i) for i in self.ids])
        """the cameras (fault hooks ``beta``, ``misalignment``: ``faults/hardware.py``)"""

    def step(self, now: Sensed) -> None:
        images = self.cameras.images(now.rel_lvlh[:, :3], now.q_lvlh_body)
        for i, (sc_id, img) in enumerate(zip(self.ids, images, strict=True)):
            self.publish(cat.CAMERA_IMAGE, i, CameraImage.of_arrays(
                topics.SIM, now.t_s, sc_id, img.poi, img.precision))
