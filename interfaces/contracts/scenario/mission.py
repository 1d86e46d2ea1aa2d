"""The mission's world: the target's orbit, the target and its POIs, the camera model."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from interfaces.contracts.scenario.base import Section


class Orbit(Section):
    """Target (chief) orbit: circular at ``altitude_km``, inclined ``inclination_deg``, its
    ascending node at right ascension ``raan_deg`` and the target ``arg_latitude_deg`` past it
    at t = 0.  The node and the argument of latitude matter to the relative motion only with
    J2 (the latter) and to the ground passes (both)."""

    altitude_km: float = Field(default=500.0, gt=100.0, lt=40000.0)
    inclination_deg: float = Field(default=51.6, ge=0.0, le=180.0)
    raan_deg: float = Field(default=0.0, ge=0.0, lt=360.0)
    arg_latitude_deg: float = Field(default=0.0, ge=0.0, lt=360.0)
    j2: bool = Field(default=False, description="include J2 in the truth dynamics")


class Target(Section):
    """The target spacecraft and its points of interest (POIs), spread uniformly on its surface;
    each POI has prior variance ``prior_variance`` (w) and importance 1/``pois`` (φ)."""

    shape: Literal["sphere"] = "sphere"
    radius_m: float = Field(default=5.0, gt=0.0)
    pois: int = Field(default=5000, ge=1, le=200_000,
                      description="points of interest on the target (at most 200,000: four "
                                  "times the 50,000 of the scaling target)")
    prior_variance: float = Field(default=1.0, gt=0.0, description="w, per POI")


class CameraSettings(Section):
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
