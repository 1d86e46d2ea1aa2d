"""The wire form of an image's POI set and precisions: packed strings, exact to the bit.

An image's POI indices and measured precisions σ⁻¹ (Eq. 5) travel as two strings, each a
codec name, a colon and base64 bytes (docs/architecture.md, "Packed POI sets"):

* **POI indices.**  ``d16:`` for an ascending set whose first index and steps are below 2¹⁶
  (every camera image): the steps as uint16, low bytes then high bytes; ``i64:`` for any
  other list: the indices as little-endian int64.
* **Precisions.**  ``dec:`` when every value is a decimal of ``PRECISION_DIGITS`` significant
  digits, as :func:`quantise` makes them: the mantissa n as a little-endian 24-bit integer in
  three byte planes and the exponent k as an int8 plane, the value being the double n / 10^k
  (n·10^-k for k < 0), the operation :func:`quantise` rounds with; ``f64:`` otherwise: the
  doubles' eight byte planes.  :func:`pack_precision` decodes what it made and keeps ``dec:``
  only when every value comes back bit for bit, so either way the values are exact.

The byte planes put bytes of one kind together (the high bytes of the steps are mostly zero,
the exponents take a few values), which the archive's zstd compresses.  A camera image of
1,100 POIs is about 9 kB instead of 27 kB of JSON lists.

A measured precision carries ``PRECISION_DIGITS`` significant digits: far below the camera's
noise (5% by default).  The digits are the information floor of the images: 2.4 bytes per
POI after zstd, against 5.7 for the JSON lists.
"""

from __future__ import annotations

import base64
import binascii

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

PRECISION_DIGITS = 6
"""Significant digits of a measured σ⁻¹ (the camera noise is 5% by default)."""

_MAX_STEP = 1 << 16
_MAX_MANTISSA = 1 << 24
_MAX_POW10 = 22
"""Largest k with 10^k an exact double."""
_POW10 = 10.0 ** np.arange(128)
"""10^|k| for every int8 exponent (exact up to 10^22)."""


def quantise(values: FloatArray, digits: int = PRECISION_DIGITS) -> FloatArray:
    """Round positive ``values`` to ``digits`` significant digits, as the nearest doubles of the
    rounded decimals (n / 10^k with an exact power of ten), so their shortest decimal form has
    at most ``digits`` digits.  Zeros stay zero."""
    out = np.zeros_like(values)
    pos = values > 0.0
    k = digits - 1 - np.floor(np.log10(values[pos]))
    scale = 10.0 ** np.abs(k)
    v = values[pos]
    out[pos] = np.where(k >= 0, np.round(v * scale) / scale, np.round(v / scale) * scale)
    return out


def packed_length(count: int) -> int:
    """Longest packed string of ``count`` values (either field, either codec)."""
    return 4 + 4 * -(-8 * count // 3)


# --- POI indices -------------------------------------------------------------------------------

def pack_poi(poi: npt.ArrayLike) -> str:
    """The packed string of the POI indices ``poi`` (integers)."""
    idx = np.asarray(poi, dtype=np.int64).reshape(-1)
    steps = np.diff(idx, prepend=0)
    if len(idx) == 0 or (idx[0] >= 0 and bool(((steps >= 0) & (steps < _MAX_STEP)).all())):
        return "d16:" + _b64(_planes(steps.astype("<u2")))
    return "i64:" + _b64(idx.astype("<i8").tobytes())


def unpack_poi(packed: str) -> IntArray:
    """The POI indices of a packed string (int64).  Raises ValueError if it is not one."""
    codec, raw = _split(packed)
    if codec == "d16":
        return _unplanes(raw, np.dtype("<u2")).astype(np.int64).cumsum()
    if codec == "i64":
        return np.frombuffer(_whole(raw, 8), dtype="<i8").astype(np.int64)
    raise ValueError(f"unknown POI codec {codec!r} (d16 or i64)")


# --- precisions --------------------------------------------------------------------------------

def pack_precision(precision: npt.ArrayLike) -> str:
    """The packed string of the precisions ``precision`` (floats): ``dec:`` when it gives them
    back bit for bit, else ``f64:``."""
    values = np.asarray(precision, dtype=np.float64).reshape(-1)
    decimal = _decimal(values)
    if decimal is not None:
        return decimal
    return "f64:" + _b64(_planes(values.astype("<f8")))


def unpack_precision(packed: str) -> FloatArray:
    """The precisions of a packed string (float64).  Raises ValueError if it is not one."""
    codec, raw = _split(packed)
    if codec == "dec":
        planes = np.frombuffer(_whole(raw, 4), dtype=np.uint8)
        n = len(planes) // 4
        low, mid, high = planes[:3 * n].reshape(3, n).astype(np.uint32)
        return _from_decimal(low | (mid << 8) | (high << 16), planes[3 * n:].view(np.int8))
    if codec == "f64":
        return _unplanes(raw, np.dtype("<f8")).astype(np.float64)
    raise ValueError(f"unknown precision codec {codec!r} (dec or f64)")


def _decimal(values: FloatArray) -> str | None:
    """``dec:`` of ``values`` if every one comes back bit for bit, else None."""
    if not bool(np.isfinite(values).all()) or bool((values < 0.0).any()):
        return None
    pos = values > 0.0
    k = np.zeros(len(values), dtype=np.int64)
    with np.errstate(divide="ignore"):
        k[pos] = PRECISION_DIGITS - 1 - np.floor(np.log10(values[pos])).astype(np.int64)
    if bool((np.abs(k) > _MAX_POW10).any()):
        return None
    scale = _POW10[np.abs(k)]
    m = np.round(values * scale if k.min(initial=0) >= 0 else
                 np.where(k >= 0, values * scale, values / scale))
    if bool((m >= _MAX_MANTISSA).any()):
        return None
    m = m.astype("<u4")
    k8 = k.astype(np.int8)
    if not np.array_equal(_from_decimal(m, k8).view(np.int64), values.view(np.int64)):
        return None
    planes = m.view(np.uint8).reshape(-1, 4)[:, :3].T.tobytes()
    return "dec:" + _b64(planes + k8.tobytes())


def _from_decimal(m: npt.NDArray[np.uint32], k: npt.NDArray[np.int8]) -> FloatArray:
    """n / 10^k (n · 10^-k for k < 0), as :func:`quantise` rounds."""
    n = m.astype(np.float64)
    if k.min(initial=0) >= 0:  # every precision below 10^6: one division
        return n / _POW10[k]
    scale = _POW10[np.abs(k.astype(np.int64))]
    return np.where(k >= 0, n / scale, n * scale)


# --- bytes -------------------------------------------------------------------------------------

def _planes(a: np.ndarray) -> bytes:
    """The bytes of ``a`` by plane: every element's first byte, then every second byte, ..."""
    return a.view(np.uint8).reshape(-1, a.itemsize).T.tobytes()


def _unplanes(raw: bytes, dtype: np.dtype) -> np.ndarray:
    """The array of ``dtype`` whose :func:`_planes` are ``raw``."""
    planes = np.frombuffer(_whole(raw, dtype.itemsize), dtype=np.uint8)
    return planes.reshape(dtype.itemsize, -1).T.copy().view(dtype).reshape(-1)


def _whole(raw: bytes, width: int) -> bytes:
    """``raw``, checked to hold whole values of ``width`` bytes."""
    if len(raw) % width:
        raise ValueError(f"{len(raw)} bytes are not whole values of {width} bytes")
    return raw


def _b64(raw: bytes) -> str:
    return base64.b64encode(raw).decode("ascii")


def _split(packed: str) -> tuple[str, bytes]:
    """(codec, bytes) of a packed string.  Raises ValueError if it is not one."""
    codec, colon, text = packed.partition(":")
    if not colon:
        raise ValueError("a packed list is '<codec>:<base64>'")
    try:
        return codec, base64.b64decode(text, validate=True)
    except binascii.Error as exc:
        raise ValueError(f"not base64: {exc}") from exc
