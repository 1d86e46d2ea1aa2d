"""Quaternion algebra on plain numpy arrays, for the onboard attitude loop.

scipy's :class:`~scipy.spatial.transform.Rotation` costs 20-70 µs per construction, product or
``apply`` since scipy 1.15 (array-API dispatch), which dominated the 10 Hz attitude cycle.  These
functions do the same algebra on a (4,) array with Python-float arithmetic (a few µs per call) and
on batches ``(..., 4)`` with numpy.

Conventions (identical to scipy's, so results agree with ``Rotation`` to rounding):

* quaternions are scalar-last ``q = [x, y, z, w]``; a unit quaternion represents the rotation
  ``R(q)`` that ``Rotation.from_quat(q).apply`` performs (active: ``R(q) v`` is v rotated);
* Hamilton product, so that ``R(p ⊗ q) = R(p) R(q)`` (the quaternion of ``r_p * r_q``);
* rotation vectors ``φ = θ n`` (rad), ``Exp(φ) = [sin(θ/2) n, cos(θ/2)]`` and ``Log`` its inverse
  on the short way (``θ ∈ [0, π]``).

References: Sola, "Quaternion kinematics for the error-state Kalman filter", arXiv:1711.02508,
2017 (Chs. 1-2: product, exponential and logarithm, rotation of a vector, attitude matrix);
Markley & Crassidis, *Fundamentals of Spacecraft Attitude Determination and Control*, 2014,
Ch. 2 (quaternion attitude representation, conversion from a matrix); Shepperd, "Quaternion
from rotation matrix", JGCD 1(3), 1978.

:func:`cross` (the vector product) is here too, for the same reason.

Shapes: every function takes one quaternion (4,) / vector (3,) or a batch with leading axes
(``(..., 4)``, ``(..., 3)``), broadcast against each other; single inputs return 1-D arrays.
Lists are accepted.  The inner functions do no validation (shape errors surface as numpy or
unpacking errors): callers check their inputs once.  Functions marked "unit" assume unit
quaternions (:func:`normalize` first when in doubt).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = [
    "canonical",
    "conj",
    "cross",
    "exp",
    "from_matrix",
    "log",
    "mul",
    "normalize",
    "rotate",
    "rotate_inv",
    "to_matrix",
]

FloatArray = npt.NDArray[np.float64]
# One component of a single quaternion/vector (a Python float) or of a batch (an array).
_Part = Any

# Below this rotation angle (rad) Exp uses the Taylor series of sin(θ/2)/θ (as scipy does); the
# first neglected term, θ⁶/645120, is below 2e-24 there.
EXP_SERIES_RAD = 1e-3


def _parts(a: FloatArray) -> list[_Part]:
    """Components along the last axis: Python floats for a 1-D array, else array views."""
    if a.ndim == 1:
        return a.tolist()  # type: ignore[no-any-return]
    return list(np.moveaxis(a, -1, 0))


def _pack(parts: tuple[_Part, ...] | list[_Part], single: bool) -> FloatArray:
    """Inverse of :func:`_parts`: stack components along a new last axis."""
    if single:
        return np.array(parts)
    return np.stack(np.broadcast_arrays(*parts), axis=-1)


def hamilton(p: Sequence[_Part], q: Sequence[_Part]) -> tuple[_Part, _Part, _Part, _Part]:
    """Components of p ⊗ q: ``[p_w q_v + q_w p_v + p_v × q_v, p_w q_w − p_v·q_v]``, the
    components given as x, y, z, w: plain arithmetic that a compiled kernel compiles as it is
    (``fsw/lib/attitude_rows.py``), so the two give the same bits as :func:`mul`."""
    px, py, pz, pw = p
    qx, qy, qz, qw = q
    return (
        pw * qx + qw * px + py * qz - pz * qy,
        pw * qy + qw * py + pz * qx - px * qz,
        pw * qz + qw * pz + px * qy - py * qx,
        pw * qw - px * qx - py * qy - pz * qz,
    )


def _rotated(q: list[_Part], v: list[_Part], sign: float) -> tuple[_Part, _Part, _Part]:
    """Components of R(q) v (sign +1) or R(q)ᵀ v (sign −1) for a unit q.

    ``t = 2 q_v × v``, ``R(q) v = v + q_w t + q_v × t`` (``q ⊗ [v, 0] ⊗ q*`` expanded,
    Sola 2017); the inverse uses the conjugate ``[−q_v, q_w]``.
    """
    qx, qy, qz, qw = q
    qx, qy, qz = sign * qx, sign * qy, sign * qz
    vx, vy, vz = v
    tx = 2.0 * (qy * vz - qz * vy)
    ty = 2.0 * (qz * vx - qx * vz)
    tz = 2.0 * (qx * vy - qy * vx)
    return (
        vx + qw * tx + qy * tz - qz * ty,
        vy + qw * ty + qz * tx - qx * tz,
        vz + qw * tz + qx * ty - qy * tx,
    )


def cross(a: npt.ArrayLike, b: npt.ArrayLike) -> FloatArray:
    """Vector product ``a × b``, (3,) or (..., 3) (np.cross costs ~10-50 µs per call)."""
    aa = np.asarray(a, dtype=float)
    ba = np.asarray(b, dtype=float)
    ax, ay, az = _parts(aa)
    bx, by, bz = _parts(ba)
    return _pack((ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx),
                 aa.ndim == 1 and ba.ndim == 1)


def mul(p: npt.ArrayLike, q: npt.ArrayLike) -> FloatArray:
    """Hamilton product ``p ⊗ q`` (the rotation ``R(p) R(q)``), (4,) or (..., 4).

    Not necessarily unit: the product of unit quaternions is unit to rounding.
    """
    pa = np.asarray(p, dtype=float)
    qa = np.asarray(q, dtype=float)
    return _pack(hamilton(_parts(pa), _parts(qa)), pa.ndim == 1 and qa.ndim == 1)


def conj(q: npt.ArrayLike) -> FloatArray:
    """Conjugate ``[−q_v, q_w]`` (for a unit q the inverse rotation), (4,) or (..., 4)."""
    qa = np.asarray(q, dtype=float)
    if qa.ndim == 1:
        x, y, z, w = qa.tolist()
        return np.array([-x, -y, -z, w])
    out: FloatArray = np.concatenate([-qa[..., :3], qa[..., 3:]], axis=-1)
    return out


def _rotate(q: npt.ArrayLike, v: npt.ArrayLike, sign: float) -> FloatArray:
    qa = np.asarray(q, dtype=float)
    va = np.asarray(v, dtype=float)
    return _pack(_rotated(_parts(qa), _parts(va), sign), qa.ndim == 1 and va.ndim == 1)


def rotate(q: npt.ArrayLike, v: npt.ArrayLike) -> FloatArray:
    """``R(q) v`` for a unit q (``Rotation.from_quat(q).apply(v)``), (3,) or (..., 3).

    Units of v are kept (m, rad/s, ...).
    """
    return _rotate(q, v, 1.0)


def rotate_inv(q: npt.ArrayLike, v: npt.ArrayLike) -> FloatArray:
    """``R(q)ᵀ v`` for a unit q (``Rotation.from_quat(q).apply(v, inverse=True)``).

    Shapes as :func:`rotate`, (3,) or (..., 3); units of v are kept.
    """
    return _rotate(q, v, -1.0)


def normalize(q: npt.ArrayLike) -> FloatArray:
    """``q / |q|``, (4,) or (..., 4).

    Raises:
        ValueError: a zero quaternion (no rotation can be assigned to it).
    """
    qa = np.asarray(q, dtype=float)
    if qa.ndim == 1:
        norm = math.hypot(*qa.tolist())
        if norm == 0.0:
            raise ValueError("cannot normalise a zero quaternion")
        return qa / norm
    norms = np.sqrt(np.sum(qa * qa, axis=-1, keepdims=True))
    if np.any(norms == 0.0):
        raise ValueError("cannot normalise a zero quaternion")
    out: FloatArray = qa / norms
    return out


def canonical(q: npt.ArrayLike) -> FloatArray:
    """The sign of q with a non-negative scalar part (same rotation), (4,) or (..., 4).

    A quaternion with ``w = 0`` exactly (a half turn) is returned unchanged: both signs are then
    canonical in this sense (scipy's ``as_quat(canonical=True)`` would further make the first
    non-zero of x, y, z positive; :func:`log` follows scipy there).  Always a new array.
    """
    qa = np.asarray(q, dtype=float)
    if qa.ndim == 1:
        return -qa if qa[3] < 0.0 else qa.copy()
    out: FloatArray = np.where(qa[..., 3:4] < 0.0, -qa, qa)
    return out


def exp_xyz(x: float, y: float, z: float) -> tuple[float, float, float, float]:
    """:func:`exp` of one rotation vector (x, y, z), rad, as a tuple: plain arithmetic that
    the compiled attitude kernels compile as it is (``fsw/lib/attitude_kernels.py``), so the
    two share one text."""
    theta = math.sqrt(x * x + y * y + z * z)
    if theta < EXP_SERIES_RAD:
        t2 = theta * theta
        s = 0.5 - t2 / 48.0 + t2 * t2 / 3840.0
    else:
        s = math.sin(0.5 * theta) / theta
    return s * x, s * y, s * z, math.cos(0.5 * theta)


def exp(rotvec: npt.ArrayLike) -> FloatArray:
    """Unit quaternion of a rotation vector, ``Exp(φ) = [sin(θ/2) φ/θ, cos(θ/2)]``, θ = |φ|.

    Args:
        rotvec: rotation vector(s) φ, rad, (3,) or (..., 3); any magnitude (θ > π gives the
            same rotation as 2π − θ about −φ, with ``w < 0``, exactly as scipy's
            ``from_rotvec``).

    Returns:
        Quaternion(s) (4,) or (..., 4).  Below θ = 1e-3 rad the factor sin(θ/2)/θ is taken
        from its Taylor series ``1/2 − θ²/48 + θ⁴/3840`` (scipy's choice), so the result is
        exact to rounding down to θ = 0.
    """
    va = np.asarray(rotvec, dtype=float)
    if va.ndim == 1:
        return np.array(exp_xyz(*va.tolist()))
    theta = np.sqrt(np.sum(va * va, axis=-1, keepdims=True))
    small = theta < EXP_SERIES_RAD
    t2 = theta * theta
    s = np.where(small, 0.5 - t2 / 48.0 + t2 * t2 / 3840.0,
                 np.sin(0.5 * theta) / np.where(small, 1.0, theta))
    out: FloatArray = np.concatenate([s * va, np.cos(0.5 * theta)], axis=-1)
    return out


def log(q: npt.ArrayLike) -> FloatArray:
    """Rotation vector of a quaternion, the short way: ``Log(q) = θ n`` with θ ∈ [0, π], rad.

    With q taken with ``w ≥ 0``, ``θ = 2 atan2(|q_v|, w)`` and
    ``Log(q) = (θ/|q_v|) q_v``.  ``atan2(s, w)/s`` is evaluated as such: atan2 keeps full
    relative precision for tiny s, so no series is needed near θ = 0 (the only special case is
    ``q_v = 0``, where the result is 0); near θ = π (w → 0) atan2 is well conditioned and the
    axis comes from q_v, which has norm ≈ 1 there.  For ``w = 0`` exactly (θ = π, where φ and
    −φ are the same rotation) the sign is scipy's: the first non-zero of x, y, z of the result is
    positive.  The result does not depend on |q|, so a
    non-unit (non-zero) q is fine.

    Args:
        q: quaternion(s) (4,) or (..., 4), either sign.

    Returns:
        Rotation vector(s), rad, (3,) or (..., 3).
    """
    qa = np.asarray(q, dtype=float)
    if qa.ndim == 1:
        x, y, z, w = qa.tolist()
        if w < 0.0 or (w == 0.0 and next((c for c in (x, y, z) if c != 0.0), 0.0) < 0.0):
            x, y, z, w = -x, -y, -z, -w
        s = math.hypot(x, y, z)
        k = 2.0 * math.atan2(s, w) / s if s > 0.0 else 2.0 / w
        return np.array([k * x, k * y, k * z])
    # first non-zero of x, y, z (0 when all are) decides the sign at w = 0
    lead = np.take_along_axis(qa[..., :3], np.argmax(qa[..., :3] != 0.0, axis=-1)[..., None], -1)
    w_raw = qa[..., 3:4]
    flip = (w_raw < 0.0) | ((w_raw == 0.0) & (lead < 0.0))
    qc = np.where(flip, -qa, qa)
    v, w = qc[..., :3], qc[..., 3:4]
    s = np.sqrt(np.sum(v * v, axis=-1, keepdims=True))
    nonzero = s > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(nonzero, 2.0 * np.arctan2(s, w) / np.where(nonzero, s, 1.0), 2.0 / w)
    out: FloatArray = k * v
    return out


def to_matrix(q: npt.ArrayLike) -> FloatArray:
    """Attitude matrix ``R(q)`` of a unit quaternion (``Rotation.as_matrix``), (3, 3)/(..., 3, 3).

    ``R = (w² − |v|²) I + 2 v vᵀ + 2 w [v×]`` (Markley & Crassidis 2014, Ch. 2, whose attitude
    matrix is the transpose: they map reference to body components).
    """
    qa = np.asarray(q, dtype=float)
    x, y, z, w = _parts(qa)
    xx, yy, zz, ww = x * x, y * y, z * z, w * w
    xy, xz, yz, xw, yw, zw = x * y, x * z, y * z, x * w, y * w, z * w
    rows = (
        (ww + xx - yy - zz, 2.0 * (xy - zw), 2.0 * (xz + yw)),
        (2.0 * (xy + zw), ww - xx + yy - zz, 2.0 * (yz - xw)),
        (2.0 * (xz - yw), 2.0 * (yz + xw), ww - xx - yy + zz),
    )
    if qa.ndim == 1:
        return np.array(rows)
    return np.stack([_pack(row, False) for row in rows], axis=-2)


def from_matrix(m: npt.ArrayLike) -> FloatArray:
    """Unit quaternion of a rotation matrix by Shepperd's method, (4,) or (..., 4).

    Of the four expressions ``4x² = 1 + m00 − m11 − m22``, ..., ``4w² = 1 + tr m`` the largest is
    used, with the off-diagonal sums/differences giving the other components (Shepperd 1978;
    Markley & Crassidis 2014, Ch. 2), then the result is normalised.  This is the algorithm
    of scipy's ``from_matrix`` and gives the same sign: the largest-magnitude component positive.
    The input must be a proper rotation matrix to rounding (scipy would first orthogonalise a
    grossly non-orthogonal one).  A single (3, 3) matrix is done on Python floats (the sim's
    10 Hz frame), a stack in vectorised numpy; both give the same bits.
    """
    ma = np.asarray(m, dtype=float)
    if ma.shape == (3, 3):
        return _from_matrix_floats(ma.tolist())
    m00, m01, m02 = ma[..., 0, 0], ma[..., 0, 1], ma[..., 0, 2]
    m10, m11, m12 = ma[..., 1, 0], ma[..., 1, 1], ma[..., 1, 2]
    m20, m21, m22 = ma[..., 2, 0], ma[..., 2, 1], ma[..., 2, 2]
    tr = m00 + m11 + m22
    candidates = np.stack([
        np.stack([1.0 + m00 - m11 - m22, m01 + m10, m02 + m20, m21 - m12], axis=-1),
        np.stack([m01 + m10, 1.0 - m00 + m11 - m22, m12 + m21, m02 - m20], axis=-1),
        np.stack([m02 + m20, m12 + m21, 1.0 - m00 - m11 + m22, m10 - m01], axis=-1),
        np.stack([m21 - m12, m02 - m20, m10 - m01, 1.0 + tr], axis=-1),
    ], axis=-2)
    choice = np.argmax(np.stack([m00, m11, m22, tr], axis=-1), axis=-1)
    q = np.take_along_axis(candidates, choice[..., None, None], axis=-2)[..., 0, :]
    return normalize(q)


def _from_matrix_floats(rows: list[list[float]]) -> FloatArray:
    """:func:`from_matrix` of one matrix, the same operations on floats (ties go to the first
    candidate, as ``np.argmax``)."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = rows
    tr = m00 + m11 + m22
    diag = [m00, m11, m22, tr]
    choice = diag.index(max(diag))
    if choice == 0:
        q = [1.0 + m00 - m11 - m22, m01 + m10, m02 + m20, m21 - m12]
    elif choice == 1:
        q = [m01 + m10, 1.0 - m00 + m11 - m22, m12 + m21, m02 - m20]
    elif choice == 2:
        q = [m02 + m20, m12 + m21, 1.0 - m00 - m11 + m22, m10 - m01]
    else:
        q = [m21 - m12, m02 - m20, m10 - m01, 1.0 + tr]
    return normalize(np.array(q))
