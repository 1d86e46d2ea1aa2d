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

from interfaces.contracts.messages.poi_packing import (
    pack_poi,
    pack_precision,
    packed_length,
    unpack_poi,
    unpack_precision,
)

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
    """POI indices (into the target's POI list) and the precision σ⁻¹ measured on each, packed
    (:mod:`interfaces.contracts.messages.poi_packing`: exact to the bit, a third of the JSON
    lists' size).

    Build it with the lists or arrays as ``poi=`` and ``precision=`` (packed on the way in, as
    are the lists of archives written before the packing) or with the packed strings; read them
    as arrays with :attr:`poi`, :attr:`precision` or :meth:`arrays` (unpacked once per message).
    """

    spacecraft: int = Field(ge=1)
    poi_packed: str = Field(max_length=packed_length(MAX_POIS),
                            description="POI indices, packed: 'd16:' or 'i64:' and base64 "
                                        "(interfaces.contracts.messages.poi_packing)")
    precision_packed: str = Field(max_length=packed_length(MAX_POIS),
                                  description="precision of each POI σ⁻¹, 1/m², packed: 'dec:' "
                                              "or 'f64:' and base64 (same module)")

    _arrays: tuple[str, str, np.ndarray, np.ndarray] | None = PrivateAttr(default=None)

    @model_validator(mode="before")
    @classmethod
    def _pack_lists(cls, data: object) -> object:
        """``poi`` and ``precision`` given as lists or arrays, packed."""
        if not isinstance(data, dict) or not ("poi" in data or "precision" in data):
            return data
        out = {k: v for k, v in data.items() if k not in ("poi", "precision")}
        if "poi" in data:
            out["poi_packed"] = pack_poi(_numbers("poi", data["poi"], "iu"))
        if "precision" in data:
            out["precision_packed"] = pack_precision(
                _numbers("precision", data["precision"], "iuf"))
        return out

    @model_validator(mode="after")
    def _unpacked(self) -> PoiPrecisions:
        """The packed lists hold the same number of valid values (POIs ≥ 0, precisions in
        [0, MAX_PRECISION]); their arrays are kept."""
        idx = unpack_poi(self.poi_packed)
        prec = unpack_precision(self.precision_packed)
        if len(idx) != len(prec):
            raise ValueError(f"{len(idx)} POIs but {len(prec)} precisions")
        if len(idx) > MAX_POIS:
            raise ValueError(f"{len(idx)} POIs, more than {MAX_POIS}")
        if not bool((idx >= 0).all()):
            raise ValueError("POI indices must be ≥ 0")
        if not bool(((prec >= 0.0) & (prec <= MAX_PRECISION)).all()):
            raise ValueError(f"precisions must be finite, in [0, {MAX_PRECISION:g}]")
        self._keep_arrays(idx, prec, copy=False)  # unpacked afresh: no one else holds them
        return self

    def __eq__(self, other: object) -> bool:
        """Equal fields (the unpacked arrays are a cache of two of them)."""
        if not isinstance(other, PoiPrecisions):
            return NotImplemented
        return type(self) is type(other) and self.__dict__ == other.__dict__

    def __hash__(self) -> int:
        return hash((type(self), self.t_sim, self.seq, self.poi_packed))

    @property
    def poi(self) -> np.ndarray:
        """POI indices (int64, read-only)."""
        return self.arrays()[0]

    @property
    def precision(self) -> np.ndarray:
        """Precision σ⁻¹ of each POI, 1/m² (float64, read-only)."""
        return self.arrays()[1]

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """(POI indices int64, precisions float64) as read-only numpy arrays, unpacked once per
        message: in one process every subscriber of the same message shares them."""
        cached = self._arrays
        if (cached is None or cached[0] is not self.poi_packed
                or cached[1] is not self.precision_packed):  # a model_copy may carry others
            self._keep_arrays(unpack_poi(self.poi_packed),
                              unpack_precision(self.precision_packed), copy=False)
            cached = self._arrays
            assert cached is not None
        return cached[2], cached[3]

    def share_arrays(self, other: PoiPrecisions) -> None:
        """Take ``other``'s unpacked arrays, as they are (None: not unpacked yet): this
        message holds ``other``'s own packed strings."""
        self.__pydantic_private__["_arrays"] = other._arrays  # type: ignore[index]

    def _keep_arrays(self, poi: npt.ArrayLike, precision: npt.ArrayLike,
                     copy: bool = True) -> None:
        """Keep read-only ``poi`` (int64) and ``precision`` (float64), the values of the packed
        strings, as what :meth:`arrays` returns: copies, unless ``copy`` is False (arrays of
        the right types that nobody else holds)."""
        idx = np.array(poi, dtype=np.int64, copy=copy)
        prec = np.array(precision, dtype=np.float64, copy=copy)
        idx.setflags(write=False)
        prec.setflags(write=False)
        self.__pydantic_private__["_arrays"] = (  # type: ignore[index]
            self.poi_packed, self.precision_packed, idx, prec)


def _numbers(name: str, values: object, kinds: str) -> np.ndarray:
    """``values`` (a list or array of numbers of the numpy ``kinds``) as a 1-D array.  Raises
    ValueError for anything else (strings, booleans, nesting, objects)."""
    try:
        arr = np.asarray(values)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{name} must be a list of numbers: {exc}") from exc
    if arr.ndim != 1 or (arr.size and arr.dtype.kind not in kinds):
        raise ValueError(f"{name} must be a flat list of numbers, got {arr.dtype} {arr.shape}")
    if arr.size and arr.dtype.kind == "f" and not bool(np.isfinite(arr).all()):
        raise ValueError(f"{name} must be finite")
    return arr


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
