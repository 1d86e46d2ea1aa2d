"""The message base class, the physical ranges every message is held to, and the shared
form of a list of POI precisions (camera images and the observations that carry them).

Non-finite floats (NaN, inf) are rejected on construction and on receipt: a message carrying
one is invalid, is dropped and counted.  Unknown fields are rejected too.
"""

from __future__ import annotations

import math
from typing import Annotated, ClassVar, Literal

import numpy as np
import numpy.typing as npt
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, model_validator

# What a message may carry, far beyond anything the mission flies and far below what breaks a
# filter: a value outside is refused where it enters (an invalid message, dropped and counted).
MAX_RANGE_M = 1.0e5
"""Largest relative position component, m (the HCW model is meaningless long before)."""


MAX_SPEED_MPS = 1.0e3
"""Largest relative velocity component, m/s."""


MAX_ACCEL_MPS2 = 10.0
"""Largest commanded or planned acceleration component, m/s²."""


MAX_RATE_RADPS = 10.0
"""Largest body rate or gyro bias component, rad/s."""


MAX_FORCE_N = 10.0
"""Largest thrust command component, N (the thrusters give tens of mN)."""


MAX_TORQUE_NM = 1.0
"""Largest torque command component, N·m (the wheels give a few mN·m)."""


MAX_TIME_S = 1.0e8
"""Latest simulation time a message may carry, s (three years)."""


MAX_PRECISION = 1.0e12
"""Largest per-POI precision (information, 1/m²)."""


MAX_ANGLE_RAD = math.pi
"""Largest angle or angular 1σ, rad."""


def _vector(n: int, limit: float) -> type[list[float]]:
    """A list of n floats, each within ±limit."""
    item = Annotated[float, Field(ge=-limit, le=limit)]
    return Annotated[list[item], Field(min_length=n, max_length=n)]  # type: ignore[valid-type,return-value]


Position = _vector(3, MAX_RANGE_M)
"""LVLH position, m."""


Velocity = _vector(3, MAX_SPEED_MPS)
"""LVLH velocity, m/s."""


Accel = _vector(3, MAX_ACCEL_MPS2)
"""LVLH acceleration, m/s²."""


Rate = _vector(3, MAX_RATE_RADPS)
"""Body rate, rad/s."""


Momentum = _vector(3, 1.0e3)
"""Angular momentum, body axes, N·m·s."""


Force = _vector(3, MAX_FORCE_N)
"""Body force, N."""


Torque = _vector(3, MAX_TORQUE_NM)
"""Body torque, N·m."""


State6 = _vector(6, MAX_RANGE_M)
"""[x y z vx vy vz] (m, m/s); StateEstimate holds the velocity part to MAX_SPEED_MPS."""


Quat = _vector(4, 1.0 + 1e-9)
"""Quaternion, scalar last [x, y, z, w] (scipy and Foxglove convention)."""


Mat6 = Annotated[list[_vector(6, MAX_RANGE_M**2)], Field(  # type: ignore[valid-type]
    min_length=6, max_length=6)]
"""6x6 covariance (m², m²/s, m²/s²)."""


Time = Annotated[float, Field(ge=0.0, le=MAX_TIME_S)]
"""Simulation time, s."""


Angle = Annotated[float, Field(ge=0.0, le=MAX_ANGLE_RAD)]
"""Non-negative angle or angular 1σ, rad."""


RateGroupName = Literal["high", "mid", "low"]


class Message(BaseModel):
    """Base of every bus message.  Immutable once built (the in-process bus hands the same
    object to every subscriber); the Bus stamps sender, seq and t_wall on publish (``stamp``)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)
    WALL_CLOCK_FIELDS: ClassVar[frozenset[str]] = frozenset({"t_wall"})
    """Fields that measure the wall clock (not reproducible); subclasses may add their own."""

    sender: str = Field(max_length=64, description="node that published the message")
    seq: int = Field(default=0, ge=0, description="per-key sequence count, set by the Bus")
    t_sim: float = Field(ge=0.0, le=MAX_TIME_S, description="simulation time of the message, s")
    t_wall: float = Field(default=0.0,
                          description="publisher wall clock, UNIX s (not reproducible)")


def stamp(msg: Message, sender: str, seq: int, t_wall: float) -> None:
    """Set the Bus's fields of a message being published (the one write to a frozen message:
    the values are the Bus's own, valid by construction)."""
    fields = msg.__dict__
    fields["sender"], fields["seq"], fields["t_wall"] = sender, seq, t_wall
    msg.__pydantic_fields_set__.update(("sender", "seq", "t_wall"))


MAX_POIS = 1_000_000
"""Most POIs one image or observations message may carry."""


def header_ok(sender: object, t_sim: object) -> bool:
    """Whether ``sender`` and ``t_sim`` pass :class:`Message`'s rules."""
    return (type(sender) is str and len(sender) <= 64 and type(t_sim) is float
            and 0.0 <= t_sim <= MAX_TIME_S)


class PoiPrecisions(Message):
    """POI indices (into the target's POI list) and the precision σ⁻¹ measured on each."""

    spacecraft: int = Field(ge=1)
    poi: list[Annotated[int, Field(ge=0)]] = Field(max_length=MAX_POIS)
    precision: list[Annotated[float, Field(ge=0.0, le=MAX_PRECISION)]] = Field(
        max_length=MAX_POIS)

    _arrays: tuple[list[int], np.ndarray, np.ndarray] | None = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _same_length(self) -> PoiPrecisions:
        if len(self.poi) != len(self.precision):
            raise ValueError("poi and precision must have the same length")
        return self

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """``poi`` (int64) and ``precision`` (float64) as read-only numpy arrays, converted once
        per message: in one process every subscriber of the same message shares them."""
        cached = self._arrays
        if cached is None or cached[0] is not self.poi:  # a model_copy may carry another list
            self._keep_arrays(self.poi, self.precision)
            cached = self._arrays
            assert cached is not None
        return cached[1], cached[2]

    def share_arrays(self, other: PoiPrecisions) -> None:
        """Take ``other``'s converted arrays, as they are (None: not converted yet): this
        message holds ``other``'s own lists."""
        self.__pydantic_private__["_arrays"] = other._arrays  # type: ignore[index]

    def _keep_arrays(self, poi: npt.ArrayLike, precision: npt.ArrayLike) -> None:
        """Keep read-only copies of ``poi`` (int64) and ``precision`` (float64), equal to the
        lists, as what :meth:`arrays` returns."""
        idx = np.array(poi, dtype=np.int64)
        prec = np.array(precision, dtype=np.float64)
        idx.setflags(write=False)
        prec.setflags(write=False)
        self.__pydantic_private__["_arrays"] = (self.poi, idx, prec)  # type: ignore[index]


Unjudged = Literal["store_overflow", "aboard", "lost", "not_heard", "lossy", "crosslink_loss",
                   "crosslink_shortfall", "no_plan", "camera_off", "no_images", "out_of_range",
                   "not_tracking", "plan_unknown", "transfer", "excluded"]
"""Why a window, or the H_i report at its end, has no decision (docs/fdir.md, "Lost is not
corrupt"): its reports lost to the store's overflow (``store_overflow``) or still aboard
(``aboard``); too many of the observers' observations lost for the report's recomputation
(``lost``: since the start; ``lossy``: in an observer's latest window, beyond what its link
explains); an observer not heard from since the window's start (``not_heard``); the
crosslinks' nominal loss (``crosslink_loss``) or the share of its neighbours' images an
observer fused (``crosslink_shortfall``) beyond what the recomputation allows; no plan in
force; its camera turned off aboard; no image received; none expected, its plan putting it
beyond the relay's reach (``out_of_range``: ``comms.range_m`` of the target); no image taken
while tracking; a transfer whose plan never reached the judge (``plan_unknown``), or any
transfer (``transfer``: the neighbours judge only held PROs); an observer its neighbours left
out of their fusion (``excluded``)."""
