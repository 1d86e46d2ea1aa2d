"""The constants a scenario implies, computed once in one place: the target's orbit (mean
motion, orbit radius), the camera model (Eq. 5, 14), the POIs on the target and the camera's
boresight in the body frame.  Every node's apps get them from their context
(``AppContext.constants``, built once per node by ``interfaces/runtime/assembly.py``); the sim
and the offline tools call :meth:`MissionConstants.of`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gnc.constants import R_EARTH_M
from gnc.hcw import mean_motion
from gnc.infocost import Camera
from gnc.poi import sphere_pois
from interfaces.contracts.scenario import Scenario


@dataclass(frozen=True)
class MissionConstants:
    """Attributes:
        n_rad_s: the target's mean motion (circular orbit at ``orbit.altitude_km``), rad/s.
        chief_radius_m: the target's orbit radius, R_E + altitude, m.
        camera: the nominal camera model (``[camera]``: half angle, range, variance scale k).
        poi_pos: the target's POIs (N, 3), target frame, m (``gnc/poi.py``).
        poi_normal: their outward unit normals (N, 3).
        boresight_body: the camera boresight in the body frame, unit vector.
    """

    n_rad_s: float
    chief_radius_m: float
    camera: Camera
    poi_pos: np.ndarray
    poi_normal: np.ndarray
    boresight_body: np.ndarray

    @classmethod
    def of(cls, scenario: Scenario) -> MissionConstants:
        altitude_m = scenario.orbit.altitude_km * 1e3
        cam = scenario.camera
        pos, normal = sphere_pois(scenario.target.pois, scenario.target.radius_m)
        bore = np.array(scenario.attitude.boresight_body, dtype=float)
        return cls(mean_motion(altitude_m), R_EARTH_M + altitude_m,
                   Camera(math.radians(cam.half_angle_deg), cam.max_range_m, cam.k),
                   pos, normal, bore / np.linalg.norm(bore))
