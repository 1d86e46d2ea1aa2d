"""Information cost of an inspection: camera visibility, per-observation precision, fused POI
variance, the per-agent decomposition and its gradient.

Source: the task-aware FDIR paper (/work/shared/paper.md), Eq. 4-8 and 14-17, which uses the
"information per pixel" cost of Schwager, Julian & Rus (ICRA 2009; Proc. IEEE 99(9), 2011).

Conventions: N observers (cameras), M points of interest (POIs); SI units (m, rad); every array
is float64.  Positions are in the target/LVLH frame (x radial, y along-track, z cross-track), the
target at the origin.

* One observation of POI ``s`` by a camera at ``p`` has variance ``σ = k·dist²(p, s)`` when ``s``
  is visible, else ``σ = ∞`` (Eq. 5, Eq. 14); its precision is ``σ⁻¹`` (0 when not visible).
* Accumulated state: ``F`` (N, M), the precision agent ``i`` has accumulated on POI ``s`` (sum of
  ``σ⁻¹`` over all of its observations so far), and the prior inverse variance ``w_inv``
  (scalar or (M,)).
* Fused variance ``H_POI(s) = (w⁻¹ + Σ_i F_is)⁻¹`` (Eq. 4, 7, 15); cost ``H = Σ_s φ(s) H_POI(s)``
  (Eq. 4, 16); agent contribution ``H_i = Σ_s φ ψ F_is`` with ``ψ = H_POI²`` (Eq. 8).

Prior ``w_inv = 0`` (no prior knowledge, as in the paper's Sec. III.F example) makes ``H_POI``
infinite for a POI nobody has observed.  Choice made here: such a state is rejected with a
``ValueError`` naming the first offending POI (give ``w_inv > 0`` or observe every POI), because
an infinite cost carries no usable signal for the FDIR metric and would turn the decomposition
(``∞ · 0``) into NaN.

Everything is a pure function or a frozen dataclass; nothing touches a bus or a file.  The
kernels use (N, 3) @ (3, M) matrix products and no Python loop over POIs.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt

from gnc.checks import finite_array

__all__ = [
    "Camera",
    "agent_contributions",
    "cost_gradient",
    "h_poi",
    "information_cost",
    "precision",
    "prior_term",
    "visibility",
]

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True)
class Camera:
    """Inspection camera model (Eq. 5, 14).

    Attributes:
        half_angle_rad: half angle of the conical field of view about the boresight, rad, in
            (0, π/2).  Default 20° (0.349 rad).
        max_range_m: largest camera-POI distance at which a POI counts as seen, m (> 0).
            Default 200 m.
        k: variance scale of ``σ = k · dist²``, in (variance units)·m⁻²; ``σ⁻¹ = 1/(k d²)``.
            Default 1.0 (the paper's example value, Eq. 22).
    """

    half_angle_rad: float = math.radians(20.0)
    max_range_m: float = 200.0
    k: float = 1.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.half_angle_rad) and 0.0 < self.half_angle_rad < math.pi / 2):
            raise ValueError(f"half_angle_rad must be in (0, pi/2), got {self.half_angle_rad!r}")
        if not (math.isfinite(self.max_range_m) and self.max_range_m > 0.0):
            raise ValueError(f"max_range_m must be positive and finite, got {self.max_range_m!r}")
        if not (math.isfinite(self.k) and self.k > 0.0):
            raise ValueError(f"k must be positive and finite, got {self.k!r}")


# ----------------------------------------------------------------------------- input checks


def _rows3(name: str, value: npt.ArrayLike) -> FloatArray:
    """``value`` as a finite (R, 3) float array (R ≥ 1)."""
    shape = np.shape(value)
    rows = shape[0] if len(shape) == 2 and shape[0] >= 1 else -1
    if rows < 0:
        raise ValueError(f"{name} must have shape (R, 3) with R >= 1, got {shape}")
    return finite_array(name, value, (rows, 3))


def _unit_rows(name: str, value: npt.ArrayLike, rows: int) -> FloatArray:
    """``value`` as a finite (rows, 3) array normalised to unit rows (zero rows rejected)."""
    a = finite_array(name, value, (rows, 3))
    norm = np.linalg.norm(a, axis=1, keepdims=True)
    if np.any(norm <= 0.0):
        raise ValueError(f"{name} has a zero-length row; expected unit direction vectors")
    return a / norm


def _per_poi(name: str, value: npt.ArrayLike, m: int) -> FloatArray:
    """A non-negative finite scalar or (M,) array as an (M,) array."""
    if np.ndim(value) == 0:
        a = np.asarray(value, dtype=float)
        if not np.isfinite(a):
            raise ValueError(f"{name} must be finite, got {value!r}")
    else:
        a = finite_array(name, value, (m,))
    if np.any(a < 0.0):
        raise ValueError(f"{name} must be non-negative")
    return np.broadcast_to(a, (m,))


def _state(w_inv: npt.ArrayLike, f: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Validated (w_inv (M,), F (N, M)); F must be finite and non-negative."""
    shape = np.shape(f)
    if len(shape) != 2 or shape[0] < 1 or shape[1] < 1:
        raise ValueError(f"F must have shape (N, M) with N, M >= 1, got {shape}")
    f_arr = finite_array("F", f, shape)
    if np.any(f_arr < 0.0):
        raise ValueError("F (accumulated precision) must be non-negative")
    return _per_poi("w_inv", w_inv, shape[1]), f_arr


def _fused_variance(w_inv: FloatArray, f: FloatArray) -> FloatArray:
    """H_POI = (w⁻¹ + Σ_i F_i)⁻¹ (Eq. 7) for validated inputs; rejects infinite variances."""
    total = w_inv + f.sum(axis=0)
    unseen = np.flatnonzero(total <= 0.0)
    if unseen.size:
        raise ValueError(
            f"H_POI is infinite for POI {int(unseen[0])} ({unseen.size} in all): "
            "prior w_inv = 0 and nobody has observed it; use w_inv > 0 or observe every POI")
    return 1.0 / total


# ----------------------------------------------------------------------------- geometry

#: POIs are processed in blocks so that every (N, block) float64 temporary is at most 64 KiB:
#: below glibc's mmap threshold, such temporaries are recycled from the heap instead of being
#: mapped afresh (page faults cost ~2 µs each here, REFERENCE.md), and they stay in cache.
_BLOCK_ELEMS = 8192
TINY = float(np.finfo(np.float64).tiny)
"""The smallest squared distance a precision divides by (m²): a camera on a POI stays finite."""


@dataclass(frozen=True)
class PoiSet:
    """POIs validated once, for the many calls that image the same target: positions s
    (M, 3), m, and outward normals (M, 3) or None (no horizon test), both copied read-only
    when made.  Positions must be finite (M ≥ 1), normals finite and of the same shape.
    Normals are only used through the sign of n·(p − s), so they are not normalised; zero rows
    are rejected."""

    pos: FloatArray
    normal: FloatArray | None

    def __post_init__(self) -> None:
        s, n = checked_pois(self.pos, self.normal)
        object.__setattr__(self, "pos", _read_only(s))
        object.__setattr__(self, "normal", None if n is None else _read_only(n))

    def __getstate__(self) -> dict[str, object]:
        """The POIs without the columns made from them (a cache: a pickled set is the same
        set whether or not it has been imaged yet)."""
        return {k: v for k, v in self.__dict__.items() if k != "columns"}

    @cached_property
    def columns(self) -> tuple[FloatArray, ...]:
        """What the compiled kernel reads (``gnc.infocost_kernels``), contiguous (M,) each:
        the positions' x, y, z (m) and |s|² (m²), the normals' x, y, z and n·s (m; zeros
        without normals)."""
        sx, sy, sz = (np.ascontiguousarray(self.pos[:, k]) for k in range(3))
        n = np.zeros_like(self.pos) if self.normal is None else self.normal
        nx, ny, nz = (np.ascontiguousarray(n[:, k]) for k in range(3))
        return sx, sy, sz, sx * sx + sy * sy + sz * sz, nx, ny, nz, nx * sx + ny * sy + nz * sz


def checked_pois(poi_pos: npt.ArrayLike, poi_normal: npt.ArrayLike | None
                 ) -> tuple[FloatArray, FloatArray | None]:
    """Validated POI positions s (M, 3), m, finite (M ≥ 1), and outward normals of the same
    shape or None (:class:`PoiSet`'s rules)."""
    s = _rows3("poi_pos", poi_pos)
    if poi_normal is None:
        return s, None
    n = finite_array("poi_normal", poi_normal, s.shape)
    if not np.all((n * n) @ np.ones(3) > 0.0):  # a matrix-vector product: fast row sums
        raise ValueError("poi_normal has a zero-length row; expected outward normals")
    return s, n


def _read_only(a: FloatArray) -> FloatArray:
    """A read-only copy of ``a``."""
    out = np.array(a, dtype=float)
    out.setflags(write=False)
    return out


def checked_cameras(cam_pos: npt.ArrayLike, boresight: npt.ArrayLike, camera: Camera
                    ) -> tuple[FloatArray, FloatArray]:
    """Validated camera positions p (N, 3) and unit boresights b (N, 3) of a ``camera``."""
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a Camera, got {type(camera).__name__}")
    p = _rows3("cam_pos", cam_pos)
    return p, _unit_rows("boresight", boresight, p.shape[0])


def checked_inputs(cam_pos: npt.ArrayLike, boresight: npt.ArrayLike, poi_pos: npt.ArrayLike,
                   poi_normal: npt.ArrayLike | None, camera: Camera,
                   ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray | None]:
    """Validated camera positions p (N, 3), unit boresights b (N, 3), POIs s (M, 3), normals
    (:class:`PoiSet`)."""
    p, b = checked_cameras(cam_pos, boresight, camera)
    return (p, b, *checked_pois(poi_pos, poi_normal))


def _blocks(p: FloatArray, b: FloatArray, s: FloatArray, n: FloatArray | None, camera: Camera,
            ) -> Iterator[tuple[slice, FloatArray, BoolArray]]:
    """Yield (POI slice, d² (N, block), visible (N, block)) over blocks of POIs.

    d² = |p|² + |s|² − 2 p·s comes from one (2N, 3) @ (3, block) product together with the
    projection b·s; its rounding error is of order eps·(|p|² + |s|²), negligible when the frame
    origin is at the target as here.  Visible ⇔ b·(s − p) > 0 and (b·(s − p))² ≥ cos²α · d²
    (inside the cone, α < π/2), 0 < d² ≤ R², and, if normals are given, n·(p − s) > 0.
    """
    count, m = p.shape[0], s.shape[0]
    step = max(1, _BLOCK_ELEMS // count)
    pb = np.vstack((p, b))
    ones = np.ones(3)
    ss = (s * s) @ ones  # |s|² (M,), row sums as a matrix-vector product (fast for 3 columns)
    ns = None if n is None else (n * s) @ ones
    pp = np.einsum("ij,ij->i", p, p)[:, None]
    bp = np.einsum("ij,ij->i", b, p)[:, None]
    cos2 = math.cos(camera.half_angle_rad) ** 2
    r2 = camera.max_range_m ** 2
    for start in range(0, m, step):
        sl = slice(start, min(m, start + step))
        sb = s[sl]
        g = pb @ sb.T
        d2, proj = g[:count], g[count:]
        d2 *= -2.0
        d2 += pp
        d2 += ss[sl]
        np.maximum(d2, 0.0, out=d2)
        proj -= bp
        vis = proj > 0.0
        proj *= proj
        vis &= proj >= cos2 * d2
        vis &= d2 <= r2
        vis &= d2 > 0.0
        if n is not None and ns is not None:
            facing = p @ n[sl].T
            facing -= ns[sl]
            vis &= facing > 0.0
        yield sl, d2, vis


def visibility(cam_pos: npt.ArrayLike, boresight: npt.ArrayLike, poi_pos: npt.ArrayLike,
               poi_normal: npt.ArrayLike | None, camera: Camera) -> BoolArray:
    """Which POIs each camera sees: bool (N, M).

    POI ``s`` is visible from a camera at ``p`` with unit boresight ``b`` (normalised here) when
    it is inside the field-of-view cone (angle between ``b`` and ``s − p`` at most
    ``camera.half_angle_rad``), within range (``0 < |s − p| ≤ camera.max_range_m``) and
    front-facing (``n·(p − s) > 0``, grazing counts as not seen).

    Front-facing is exactly the self-occlusion test for a convex target: the target lies in the
    closed half-space ``n·(x − s) ≤ 0`` behind the tangent plane at ``s`` (supporting hyperplane
    of a convex body), so if ``n·(p − s) > 0`` every point of the segment from ``s`` to ``p``
    other than ``s`` lies strictly in front of that plane and outside the target; if
    ``n·(p − s) < 0`` the segment leaves ``s`` into the body's side and is blocked.  For a
    non-convex target it is necessary but not sufficient.  ``poi_normal=None`` disables it.

    Args:
        cam_pos: camera positions (N, 3), m.
        boresight: boresight directions (N, 3), unit (normalised here; zero rows rejected).
        poi_pos: POI positions (M, 3), m.
        poi_normal: outward surface normals (M, 3) (any length > 0), or None.
        camera: the camera model (cone, range).

    Raises:
        ValueError: on wrong shapes, NaN/inf, zero-length directions.
    """
    p, b, s, n = checked_inputs(cam_pos, boresight, poi_pos, poi_normal, camera)
    out = np.empty((p.shape[0], s.shape[0]), dtype=bool)
    for sl, _, vis in _blocks(p, b, s, n, camera):
        out[:, sl] = vis
    return out


def _user_mask(visible: npt.ArrayLike | None, shape: tuple[int, int]) -> BoolArray | None:
    """The caller's visibility mask, validated, or None."""
    if visible is None:
        return None
    v = np.asarray(visible)
    if v.shape != shape or v.dtype != np.bool_:
        raise ValueError(f"visible must be a bool array of shape {shape}, got {v.dtype} {v.shape}")
    return v


def _fill_precision(p: FloatArray, b: FloatArray, s: FloatArray, n: FloatArray | None,
                    camera: Camera, mask: BoolArray | None, out: FloatArray) -> FloatArray:
    """Write σ⁻¹ = 1/(k d²) where visible (camera's test or ``mask``), else 0, into ``out``."""
    inv_k = 1.0 / camera.k
    for sl, d2, vis in _blocks(p, b, s, n, camera):
        if mask is not None:
            vis = mask[:, sl]
            if np.any(vis & (d2 <= 0.0)):
                raise ValueError("a camera coincides with a POI marked visible (distance 0)")
        # 1/(k d²) everywhere, then zero where not visible: a masked divide (where=) costs
        # ~5× more.  d² is clamped to the smallest normal so a camera on a hidden POI gives
        # 4e307·0 = 0, never inf·0.
        np.maximum(d2, TINY, out=d2)
        block = out[:, sl]
        np.divide(inv_k, d2, out=block)
        block *= vis
    return out


def precision(cam_pos: npt.ArrayLike, boresight: npt.ArrayLike, poi_pos: npt.ArrayLike,
              poi_normal: npt.ArrayLike | None, camera: Camera,
              visible: npt.ArrayLike | None = None, *,
              out: FloatArray | None = None) -> FloatArray:
    """Precision of one observation per camera: σ⁻¹ (N, M) = 1/(k d²) where visible, else 0.

    Eq. 5 / Eq. 14 (σ = k·dist², ∞ when not visible).  Units: inverse variance units.

    Args:
        cam_pos, boresight, poi_pos, poi_normal, camera: as in :func:`visibility`.
        visible: optional bool (N, M) mask used instead of :func:`visibility` (e.g. all True for
            the paper's 1-DOF example, Sec. III.F).
        out: optional float64 (N, M) array to write into (reuse it in hot loops to avoid page
            faults on a fresh allocation); returned.

    Raises:
        ValueError: bad shapes/values, or a POI marked visible at distance 0.
    """
    p, b, s, n = checked_inputs(cam_pos, boresight, poi_pos, poi_normal, camera)
    shape = (p.shape[0], s.shape[0])
    if out is None:
        out = np.empty(shape)
    elif not (isinstance(out, np.ndarray) and out.shape == shape and out.dtype == np.float64):
        raise ValueError(f"out must be a float64 array of shape {shape}")
    return _fill_precision(p, b, s, n, camera, _user_mask(visible, shape), out)


# ----------------------------------------------------------------------------- cost


def h_poi(w_inv: npt.ArrayLike, F: npt.ArrayLike) -> FloatArray:
    """Fused variance of each POI, (M,): ``H_POI = (w⁻¹ + Σ_i F_i)⁻¹`` (Eq. 4, 7, 15).

    Args:
        w_inv: prior inverse variance, scalar or (M,), ≥ 0.
        F: accumulated precision (N, M), ≥ 0 (row i: all of agent i's observations so far).

    Raises:
        ValueError: bad shapes/values, or a POI with w_inv = 0 that nobody has observed
            (H_POI would be infinite; see the module docstring).
    """
    w, f = _state(w_inv, F)
    return _fused_variance(w, f)


def information_cost(phi: npt.ArrayLike, w_inv: npt.ArrayLike, F: npt.ArrayLike) -> float:
    """Information cost ``H = Σ_s φ(s) H_POI(s)`` (Eq. 4, 7, 16).

    Args:
        phi: POI importance φ ≥ 0, scalar or (M,).
        w_inv, F: as in :func:`h_poi`.
    """
    w, f = _state(w_inv, F)
    weights = _per_poi("phi", phi, f.shape[1])
    return float(weights @ _fused_variance(w, f))


def _psi_terms(phi: npt.ArrayLike, w_inv: npt.ArrayLike, F: npt.ArrayLike,
               psi: npt.ArrayLike | None) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(φψ (M,), w_inv (M,), F (N, M)) with ψ = H_POI² unless given."""
    w, f = _state(w_inv, F)
    m = f.shape[1]
    if psi is None:
        hp = _fused_variance(w, f)
        psi_arr = hp * hp
    else:
        psi_arr = _per_poi("psi", psi, m)
    return _per_poi("phi", phi, m) * psi_arr, w, f


def agent_contributions(phi: npt.ArrayLike, w_inv: npt.ArrayLike, F: npt.ArrayLike, *,
                        psi: npt.ArrayLike | None = None) -> FloatArray:
    """Per-agent contribution ``H_i = Σ_s φ(s) ψ(s) F_is`` (N,), ψ = H_POI² (Eq. 8).

    Eq. 8 sums over S_i, the POIs agent i has seen; ``F_is = 0`` elsewhere, so summing over all
    POIs is the same.  ``prior_term + Σ_i H_i = H`` exactly: ψ(s)·(w⁻¹ + Σ_i F_is)
    = H_POI(s)² / H_POI(s) = H_POI(s), so Σ_s φψ w⁻¹ + Σ_i Σ_s φψ F_is = Σ_s φ H_POI = H.

    Args:
        phi, w_inv, F: as in :func:`information_cost`.
        psi: optional (M,) or scalar ψ ≥ 0 to use instead of ψ(w_inv, F), e.g. the nominal
            state's ψ to linearise about it (ψ held fixed, as in the paper's Eq. 21: a sensor
            fault σ⁻¹ ↦ βσ⁻¹ then scales H_i of new observations by exactly β).
    """
    weight, _, f = _psi_terms(phi, w_inv, F, psi)
    return f @ weight


def prior_term(phi: npt.ArrayLike, w_inv: npt.ArrayLike, F: npt.ArrayLike) -> float:
    """Prior part of Eq. 8, ``Σ_s φ(s) ψ(s) w⁻¹(s)``, so that ``prior_term + Σ H_i = H``.

    See :func:`agent_contributions` for the one-line proof of the decomposition.
    """
    weight, w, _ = _psi_terms(phi, w_inv, F, None)
    return float(weight @ w)


def cost_gradient(cam_pos: npt.ArrayLike, boresight: npt.ArrayLike, poi_pos: npt.ArrayLike,
                  poi_normal: npt.ArrayLike | None, camera: Camera, phi: npt.ArrayLike,
                  w_inv: npt.ArrayLike, F: npt.ArrayLike, *,
                  visible: npt.ArrayLike | None = None) -> FloatArray:
    """∂H⁺/∂p_i (N, 3), m⁻¹·(cost units): gradient of the cost after each agent takes one more
    observation at its current pose, the visible set held fixed.

    With ``F⁺ = F + σ⁻¹(p)`` and ``H⁺_POI = (w⁻¹ + Σ_i F⁺_i)⁻¹``, ``H⁺ = Σ_s φ H⁺_POI``.  Since
    ∂H⁺_POI/∂p_i = −H⁺_POI² ∂σ⁻¹(p_i, s)/∂p_i and ∂(1/(k d²))/∂p_i = −2 (p_i − s)/(k d⁴)::

        ∂H⁺/∂p_i = Σ_s vis_is φ(s) H⁺_POI(s)² · 2 (p_i − s) / (k d_is⁴).

    Reduction to the paper's Eq. 17: for p_i = (x_i, 0, 0), s = (s_x, s_y, 0), all visible,
    F = 0, the x component is Σ_s φ (2/k) H_POI² (x_i − s_x)/[(x_i − s_x)² + s_y²]², with
    H_POI the fused variance of the observations at the current positions (Eq. 15).

    H is not differentiable where a POI crosses the edge of the field of view, the range limit
    or the terminator of the facing test; this is the gradient with the visible set fixed.

    Args:
        cam_pos, boresight, poi_pos, poi_normal, camera: as in :func:`visibility`.
        phi, w_inv, F: as in :func:`information_cost` (F: precision accumulated before this
            observation).
        visible: optional bool (N, M) mask used instead of :func:`visibility`.
    """
    p, b, s, n = checked_inputs(cam_pos, boresight, poi_pos, poi_normal, camera)
    shape = (p.shape[0], s.shape[0])
    mask = _user_mask(visible, shape)
    w, f = _state(w_inv, F)
    if f.shape != shape:
        raise ValueError(f"F must have shape {shape} (cameras x POIs), got {f.shape}")
    new = _fill_precision(p, b, s, n, camera, mask, np.empty(shape))
    hp = _fused_variance(w, f + new)
    coef = _per_poi("phi", phi, shape[1]) * hp * hp * (2.0 / camera.k)
    grad = np.zeros((shape[0], 3))
    for sl, d2, vis in _blocks(p, b, s, n, camera):
        weight = np.zeros_like(d2)
        np.divide(coef[None, sl], d2 * d2, out=weight, where=vis if mask is None else mask[:, sl])
        grad += weight.sum(axis=1)[:, None] * p - weight @ s[sl]
    return grad
