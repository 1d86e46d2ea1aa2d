"""Messages the sim publishes: truth, sensor measurements, camera images, fault events."""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field, model_validator

from interfaces.contracts.messages.base import (
    MAX_POIS,
    MAX_PRECISION,
    MAX_RANGE_M,
    MAX_SPEED_MPS,
    Angle,
    Message,
    PoiPrecisions,
    Position,
    Quat,
    Rate,
    Velocity,
    header_ok,
)
from interfaces.contracts.messages.poi_packing import pack_poi, pack_precision


class TruthState(Message):
    """True relative states of all observers in the target's LVLH frame (x radial, y along-track,
    z cross-track).  Used by the channel model (range) and archived as truth for evaluation.

    ``q_lvlh_body``: true attitude, the rotation taking body vectors into LVLH; ``w_body_radps``:
    true inertial angular velocity in body axes; ``dv_mps``: velocity increment delivered by the
    thrusters since the start, L1 over the body axes (Σ_j |F_j|/m·dt, what the propellant pays
    for), m/s.  Empty when the sim has no attitude.
    """

    spacecraft: list[int]
    r_lvlh_m: list[Position]
    v_lvlh_mps: list[Velocity]
    q_lvlh_body: list[Quat] = Field(default_factory=list)
    w_body_radps: list[Rate] = Field(default_factory=list)
    dv_mps: list[float] = Field(default_factory=list)


class RelNavMeasurement(Message):
    """Relative position/velocity sensor of one observer (LVLH, noisy, seeded)."""

    spacecraft: int = Field(ge=1)
    r_m: Position
    v_mps: Velocity
    sigma_r_m: float = Field(gt=0.0, le=MAX_RANGE_M)
    sigma_v_mps: float = Field(gt=0.0, le=MAX_SPEED_MPS)


class AttitudeMeasurement(Message):
    """Attitude sensors of one observer at ω_high: gyro rate (body axes, rad/s, averaged over the
    last tick) and, when the star tracker has a fix this tick, its measured attitude
    (rotation body -> ECI, scalar last) with its 1σ noise about the cross-boresight and boresight
    axes (rad)."""

    spacecraft: int = Field(ge=1)
    gyro_radps: Rate
    star_tracker: Quat | None = None
    st_sigma_cross_rad: Angle = 0.0
    st_sigma_roll_rad: Angle = 0.0

    @model_validator(mode="after")
    def _fix_is_usable(self) -> AttitudeMeasurement:
        if self.star_tracker is not None:
            if abs(math.sqrt(sum(c * c for c in self.star_tracker)) - 1.0) > 1e-3:
                raise ValueError("star_tracker must be a unit quaternion")
            if self.st_sigma_cross_rad <= 0.0 or self.st_sigma_roll_rad <= 0.0:
                raise ValueError("a star-tracker fix needs positive st_sigma_* (rad)")
        return self


class CameraImage(PoiPrecisions):
    """One inspection image of an observer (ω_mid): the POIs it saw (ascending) and the
    precision of each measurement (Eq. 5: 1/(k·dist²), with the camera's noise and health)."""

    @classmethod
    def of_arrays(cls, sender: str, t_sim: float, spacecraft: int, poi: np.ndarray,
                  precision: np.ndarray) -> CameraImage:
        """The image of ``poi`` (int) and ``precision`` (float) arrays, packed, which keeps
        copies of them as :meth:`arrays` (the same values: its subscribers unpack nothing).

        Validated on the arrays: the schema's rules checked with numpy (POIs integers ≥ 0,
        precisions finite in [0, MAX_PRECISION], equal lengths within the bound, the header's
        ranges), ~20× cheaper than pydantic on a 2,500-POI image; whatever those checks do not
        pass is validated by pydantic, which raises
        (``tests/interfaces/runtime/test_encoding.py``)."""
        idx, prec = np.asarray(poi), np.asarray(precision)
        ok = (header_ok(sender, t_sim) and type(spacecraft) is int and spacecraft >= 1
              and idx.ndim == prec.ndim == 1 and len(idx) == len(prec) <= MAX_POIS
              and np.issubdtype(idx.dtype, np.integer) and bool((idx >= 0).all())
              and np.issubdtype(prec.dtype, np.floating) and bool(np.isfinite(prec).all())
              and bool(((prec >= 0.0) & (prec <= MAX_PRECISION)).all()))
        if not ok:
            return cls(sender=sender, t_sim=t_sim, spacecraft=spacecraft, poi=idx,
                       precision=prec)
        msg = cls.model_construct(sender=sender, t_sim=t_sim, spacecraft=spacecraft,
                                  poi_packed=pack_poi(idx), precision_packed=pack_precision(prec))
        msg._keep_arrays(idx, prec)
        return msg


class FaultEvent(Message):
    """Truth of an injected fault (sim): ``kind`` on ``spacecraft`` switched on or off at
    ``t_sim``, with the scenario's ``magnitude`` and the realised parameters (``detail``:
    directions, torques, rotations; see faults/hardware.py); spacecraft 0: every observer."""

    spacecraft: int = Field(ge=0)
    kind: str = Field(max_length=64)
    active: bool
    magnitude: float | None = None
    start_s: float = Field(ge=0.0)
    end_s: float | None = None
    detail: dict[str, list[float] | float] = Field(default_factory=dict)
