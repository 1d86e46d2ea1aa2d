"""Attitude guidance: pointing, slerp plans and the SCP-refined quaternion slew.

Conventions (project-wide):

* an attitude is a scipy :class:`~scipy.spatial.transform.Rotation` ``R_ref_body``
  mapping body-frame vectors to reference-frame vectors, ``R.apply(v_body) = v_ref``;
  the reference frame is taken as inertial for the kinematics;
* quaternion arrays are scalar-last ``[x, y, z, w]`` (scipy), Hamilton product, so that
  the quaternion of ``r_a * r_b`` is ``q_a ⊗ q_b``;
* ``ω`` is the body angular velocity with respect to the inertial frame, in body axes,
  rad/s; kinematics ``Ṙ = R [ω]×``, i.e. ``q̇ = ½ q ⊗ (ω, 0)``;
* with ``ω`` constant over ``[t, t + h]`` the exact solution is
  ``q(t + h) = q(t) ⊗ Exp(ω h)``, ``Exp(φ) = [sin(|φ|/2) φ/|φ|, cos(|φ|/2)]``
  (Sola, "Quaternion kinematics for the error-state Kalman filter", 2017, Sec. 4.6).

Plans expose ``at(t) -> (Rotation, ω_body (3,), ω̇_body (3,))`` (:class:`AttitudePlan`),
which is what the tracking controller (:mod:`fsw.lib.attitude_control`) consumes.  The
per-cycle functions (``at``, :func:`repoint`) do their algebra on quaternion arrays with
:mod:`gnc.quat` and build one Rotation for the result (scipy's Rotation costs tens of µs
per operation).

The paper (Sec. II.B) plans the attitude "using a combination of slerp interpolation
and SCP with a norm constraint on the quaternions"; :func:`slerp_plan` is the first
and the initial guess of :func:`scp_slew`, the second.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt
import osqp
import scipy.sparse as sp
from scipy.spatial.transform import Rotation

from gnc import quat
from gnc.checks import finite_array

__all__ = [
    "AttitudePlan",
    "SlerpPlan",
    "SlewPlan",
    "pointing_rotation",
    "repoint",
    "scp_slew",
    "slerp_plan",
]

FloatArray = npt.NDArray[np.float64]
PlanSample = tuple[Rotation, FloatArray, FloatArray]

# A secondary direction closer than this to the line of sight (rad) is treated as
# parallel to it (see pointing_rotation).
_DEGENERATE_SECONDARY_RAD = 1e-6


class AttitudePlan(Protocol):
    """Anything that gives the desired attitude, rate and rate derivative at a time."""

    def at(self, t: float) -> PlanSample:
        """Desired attitude, rate and rate derivative at time t (s).

        Returns ``(R_ref_des, ω rad/s (3,), ω̇ rad/s² (3,))``; the rates are those
        of the desired (planned body) frame w.r.t. inertial, in its own axes.
        """
        ...

    def at_quat(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """As :meth:`at`, the attitude as its quaternion (4,), scalar last."""
        ...

    def nodes(self) -> PlanNodes:
        """The plan as its node path (:data:`PlanNodes`): what the compiled cycle over a
        fleet's attitude rows samples (``fsw.lib.attitude_rows.slew_sample``)."""
        ...


PlanNodes = tuple[FloatArray, FloatArray, FloatArray, FloatArray]
"""A plan's node path: node times s (M,), unit quaternions (M, 4), the rotation vector of
each interval (M − 1, 3), and the piecewise-constant body rates rad/s (K, 3) (``_NodePath``)."""


# ---------------------------------------------------------------------------
# input checks


def _unit3(name: str, value: npt.ArrayLike) -> FloatArray:
    """Unit vector along a finite, non-zero 3-vector, else ValueError."""
    a = finite_array(name, value, (3,))
    norm = math.hypot(*a.tolist())
    if not norm > 0.0:
        raise ValueError(f"{name} must have non-zero length")
    return a / norm


def _single_quat(name: str, r: Rotation) -> FloatArray:
    """The quaternion (4,) of one finite scipy Rotation, else ValueError."""
    if not isinstance(r, Rotation) or not r.single:
        raise ValueError(f"{name} must be a single scipy Rotation")
    q = r.as_quat()
    if not np.isfinite(q).all():
        raise ValueError(f"{name} contains NaN or infinite values")
    return q


def _single_rotation(name: str, r: Rotation) -> Rotation:
    """Check that r is one finite scipy Rotation, else ValueError."""
    _single_quat(name, r)
    return r


def _positive(name: str, value: float) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return v


def _finite(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return v


# ---------------------------------------------------------------------------
# pointing


def pointing_rotation(
    los_ref: npt.ArrayLike,
    boresight_body: npt.ArrayLike = (0.0, 0.0, 1.0),
    up_ref: npt.ArrayLike = (0.0, 0.0, 1.0),
    up_body: npt.ArrayLike = (0.0, 1.0, 0.0),
) -> Rotation:
    """Attitude that puts the boresight on a line of sight, secondary axis as close as possible.

    Solves Wahba's problem with an infinite weight on the primary pair
    (``R b = l`` exactly) and a finite one on the secondary pair (``R u_b`` as close
    as possible to ``u_r``), i.e. the TRIAD-like "align, then clock" solution;
    computed by :meth:`Rotation.align_vectors` (Markley & Crassidis, *Fundamentals of
    Spacecraft Attitude Determination and Control*, 2014, Sec. 5.2).  The best
    achievable secondary error is ``|∠(u_r, l) − ∠(u_b, b)|``.

    Degenerate secondary: when ``up_ref`` is parallel or antiparallel to the line of
    sight (within 1e-6 rad) the clocking about the line of sight is undefined; the
    fallback is the shortest-arc rotation taking the boresight onto the line of sight
    (no clocking; for an antiparallel boresight a 180° turn about an axis chosen by
    scipy).

    Args:
        los_ref: line of sight in the reference frame (any non-zero length), m or unit.
        boresight_body: camera boresight in body axes (non-zero), default body +z.
        up_ref: secondary reference direction in the reference frame (non-zero),
            default reference +z (the orbit normal in the HCW frame).
        up_body: body axis to bring close to ``up_ref`` (non-zero, not parallel to the
            boresight), default body +y.

    Returns:
        ``R_ref_body`` with ``R.apply(boresight_body) == los_ref/|los_ref|``.

    Raises:
        ValueError: zero-length or non-finite vectors, or ``up_body`` parallel to the
            boresight (the secondary axis would be meaningless).
    """
    los = _unit3("los_ref", los_ref)
    bore = _unit3("boresight_body", boresight_body)
    up_r = _unit3("up_ref", up_ref)
    up_b = _unit3("up_body", up_body)
    if np.linalg.norm(np.cross(bore, up_b)) < math.sin(_DEGENERATE_SECONDARY_RAD):
        raise ValueError("up_body must not be parallel to boresight_body")
    if np.linalg.norm(np.cross(los, up_r)) < math.sin(_DEGENERATE_SECONDARY_RAD):
        rot, _ = Rotation.align_vectors(los[None, :], bore[None, :])
        return rot
    rot, _ = Rotation.align_vectors(
        np.stack([los, up_r]), np.stack([bore, up_b]), weights=[np.inf, 1.0]
    )
    return rot


# ---------------------------------------------------------------------------
# plans


def repoint(r_prev: Rotation | npt.NDArray[np.float64], los_ref: npt.ArrayLike,
            boresight_body: npt.ArrayLike = (0.0, 0.0, 1.0)) -> Any:
    """The attitude nearest to ``r_prev`` whose boresight lies on ``los_ref``.

    ``R = Rot(a → c) · r_prev`` with ``a = r_prev · boresight`` and ``c`` the unit line of sight:
    the shortest rotation carrying the current boresight onto the line of sight (axis a × c,
    angle atan2(|a × c|, a · c)).  Applied cycle after cycle it points without ever turning
    about the boresight (roll-free pointing, the least wheel effort), and unlike a pointing
    law with a secondary axis it has no singular line of sight.  For an exactly opposite line
    of sight the half turn is taken about the body axis perpendicular to the boresight that is
    most orthogonal to it (any perpendicular axis is shortest).

    Args:
        r_prev: the previous attitude R_ref_body, a Rotation or its quaternion (4,).
        los_ref: line of sight in the reference frame (any length > 0).
        boresight_body: boresight in body axes (any length > 0).

    Returns:
        R_ref_body with ``R.apply(boresight) ∥ los_ref``, of the same kind as ``r_prev``
        (Rotation, or a unit quaternion array for the allocation-free hot path).
    """
    q_prev = quat.normalize(_single_quat("r_prev", r_prev) if isinstance(r_prev, Rotation)
                            else finite_array("r_prev", r_prev, (4,)))
    c = _unit3("los_ref", los_ref)
    b = _unit3("boresight_body", boresight_body)
    a = quat.rotate(q_prev, b)
    axis = quat.cross(a, c)
    s, cos = math.hypot(*axis.tolist()), float(a @ c)
    if s < 1e-12:
        if cos > 0.0:
            return r_prev
        e = np.eye(3)[int(np.argmin(np.abs(b)))]
        axis = quat.rotate(q_prev, quat.cross(b, e))
        turn = axis * (math.pi / math.hypot(*axis.tolist()))
    else:
        turn = axis * (math.atan2(s, cos) / s)
    q = quat.mul(quat.exp(turn), q_prev)
    return Rotation.from_quat(q) if isinstance(r_prev, Rotation) else q


@dataclass(frozen=True)
class _NodePath:
    """Attitude nodes joined by constant-rate short-way rotations (slerp).

    ``φ_k = Log(q_k⁻¹ ⊗ q_{k+1})`` (|φ_k| ≤ π) is the rotation over interval k in body
    axes, so ``q(t) = q_k ⊗ Exp(φ_k (t − t_k)/(t_{k+1} − t_k))`` is the exact kinematics of
    the constant body rate ``φ_k/(t_{k+1} − t_k)`` that carries node k onto node k+1: for a
    slerp plan that rate is the plan's ``ω``; for an SCP slew it is ``ω_k`` at convergence
    (``q_{k+1} = q_k ⊗ Exp(ω_k h)``) and differs from it by the solver tolerance otherwise,
    while φ_k keeps the attitude continuous at the nodes.  This is exactly what scipy's
    ``Slerp`` computes (Shoemake, "Animating rotation with quaternion curves", SIGGRAPH 1985),
    done once per plan instead of once per sample.

    Attributes:
        t_s: node times, s, (M,), strictly increasing.
        q: unit node quaternions, scalar-last, (M, 4), signs as given.
        phi: rotation vector of each interval, body axes, rad, (M−1, 3).
    """

    t_s: FloatArray
    q: FloatArray
    phi: FloatArray

    @classmethod
    def through(cls, t_s: FloatArray, q: npt.ArrayLike) -> _NodePath:
        """The path through quaternions q (M, 4) (any norm, either signs) at times t_s (M,).

        Raises:
            ValueError: fewer than 2 nodes, mismatched shapes or times not strictly increasing
                (what scipy's Slerp rejected).
        """
        q_unit = quat.normalize(q)
        if (t_s.ndim != 1 or t_s.shape[0] < 2 or q_unit.shape != (t_s.shape[0], 4)
                or not bool((np.diff(t_s) > 0.0).all())):
            raise ValueError(f"need M >= 2 strictly increasing node times (M,) and quaternions "
                             f"(M, 4), got {t_s.shape} and {q_unit.shape}")
        return cls(t_s=t_s, q=q_unit, phi=quat.log(quat.mul(quat.conj(q_unit[:-1]), q_unit[1:])))

    def quat_at(self, t: float) -> FloatArray:
        """Quaternion (4,) on the path at t (s), clamped to ``[t_s[0], t_s[-1]]``.

        The interval is Slerp's: ``(t_k, t_{k+1}]`` (t_0 in the first), so a node time is
        reached from the node before, and the quaternion keeps the sign of the starting
        node of its interval, exactly as scipy's Slerp returned it.
        """
        t_nodes = self.t_s
        tc = min(max(t, float(t_nodes[0])), float(t_nodes[-1]))
        k = max(int(np.searchsorted(t_nodes, tc, side="left")) - 1, 0)
        t_k, t_next = float(t_nodes[k]), float(t_nodes[k + 1])
        return quat.mul(self.q[k], quat.exp(self.phi[k] * ((tc - t_k) / (t_next - t_k))))

    def sample(self, rates: FloatArray, t: float, as_quat: bool = False) -> Any:
        """Attitude on the path and piecewise-constant body rate ``rates[k]`` (rad/s) at t (s).

        For the rate, interval k is ``[t_k, t_{k+1})``, the end time belonging to the last
        one.  Outside ``[t_s[0], t_s[-1]]`` the attitude is held at the first/last node
        and the rate is zero; ω̇ is zero throughout.  The attitude is a Rotation, or its
        quaternion (4,) with ``as_quat`` (no Rotation built: the 10 Hz loop's path).
        """
        tt = _finite("t", t)
        t_nodes = self.t_s
        zero = np.zeros(3)
        q_t = self.quat_at(tt)
        r_t = q_t if as_quat else Rotation.from_quat(q_t)
        if tt < t_nodes[0] or tt > t_nodes[-1]:
            return r_t, zero, zero.copy()
        k = int(np.searchsorted(t_nodes, tt, side="right")) - 1
        k = min(max(k, 0), len(rates) - 1)
        return r_t, rates[k].copy(), zero


@dataclass(frozen=True)
class SlerpPlan:
    """Constant-rate geodesic from ``r0`` (at ``t0_s``) to ``r1`` (at ``t1_s``).

    ``R(t) = r0 · Exp(φ (t − t0)/(t1 − t0))`` with ``φ = rotvec(r0⁻¹ r1)``,
    ``|φ| ≤ π`` (scipy's rotation vector is the short way whatever the sign of the
    quaternions given).  The body rate is constant, ``ω = φ/(t1 − t0)`` (``φ`` is the
    rotation axis, fixed in both frames along a geodesic), ``ω̇ = 0``.  Outside
    ``[t0, t1]`` the attitude is clamped to r0/r1 with zero rate.

    Attributes:
        r0: start attitude ``R_ref_body``.
        r1: end attitude ``R_ref_body``.
        t0_s: start time, s.
        t1_s: end time, s (> t0_s).
    """

    r0: Rotation
    r1: Rotation
    t0_s: float
    t1_s: float
    _path: _NodePath = field(init=False, repr=False, compare=False)
    _rate: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        q0 = _single_quat("r0", self.r0)
        q1 = _single_quat("r1", self.r1)
        t0 = _finite("t0_s", self.t0_s)
        t1 = _finite("t1_s", self.t1_s)
        if not t1 > t0:
            raise ValueError(f"t1_s must be after t0_s, got t0={t0!r}, t1={t1!r}")
        path = _NodePath.through(np.array([t0, t1]), np.stack([q0, q1]))
        object.__setattr__(self, "_path", path)
        object.__setattr__(self, "_rate", path.phi / (t1 - t0))

    @property
    def angle_rad(self) -> float:
        """Geodesic angle travelled, rad (in [0, π])."""
        return float(np.linalg.norm(self._path.phi[0]))

    def at(self, t: float) -> PlanSample:
        """Desired ``(R_ref_body, ω_body rad/s, ω̇_body rad/s²)`` at time t (s).

        ``r0 · Exp(ω (t − t0))`` on ``[t0, t1]`` (one Rotation built per call).
        """
        return self._path.sample(self._rate, t)

    def at_quat(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """As :meth:`at` with the attitude as a quaternion (4,), scalar last."""
        out: tuple[FloatArray, FloatArray, FloatArray] = self._path.sample(self._rate, t, True)
        return out

    def nodes(self) -> PlanNodes:
        """The plan as its node path (:data:`PlanNodes`): two nodes, one rate."""
        return self._path.t_s, self._path.q, self._path.phi, self._rate


def slerp_plan(r0: Rotation, r1: Rotation, t0_s: float, t1_s: float) -> SlerpPlan:
    """Constant-rate short-way geodesic plan from r0 at t0_s to r1 at t1_s (see SlerpPlan)."""
    return SlerpPlan(r0=r0, r1=r1, t0_s=float(t0_s), t1_s=float(t1_s))


@dataclass(frozen=True)
class SlewPlan:
    """Result of :func:`scp_slew`: quaternion nodes and piecewise-constant body rates.

    ``at(t)`` slerps between the nodes (``q_k ⊗ Exp(φ_k (t − t_k)/h)`` with
    ``φ_k = Log(q_k⁻¹ ⊗ q_{k+1})``, which is ``ω_k h`` at convergence) and returns the rate of the
    interval containing t (``[t_k, t_{k+1})``, the end time in the last one) with
    ``ω̇ = 0``; outside ``[t_s[0], t_s[-1]]`` the attitude is clamped to the end
    nodes and the rate is zero.  Check ``status`` before flying it.

    Attributes:
        t_s: node times, s, shape (N+1,).
        q: unit quaternions ``R_ref_body`` at the nodes, scalar-last, shape (N+1, 4)
            (renormalised; consecutive nodes in the same hemisphere).
        w: body rate on each interval, rad/s, shape (N, 3); ``|w| ≤ w_max`` per axis
            whenever at least one subproblem was solved.
        status: ``"solved"`` (rate limits met and the exact integration of ``w``
            from r0 reaches r1 within 1e-5 rad), ``"infeasible"`` (OSQP proved a
            subproblem primal infeasible: the slew needs more rate than ``w_max``
            allows), ``"not_converged"`` (``max_iters`` reached with the exact
            kinematics still missing r1 by more than 1e-5 rad), ``"solver_error"``
            (OSQP failed otherwise).  On the last two the last good iterate is
            returned; on ``"infeasible"`` at the first iteration, the slerp plan.
        converged: True when the SCP step fell below tolerance before ``max_iters``.
        iterations: number of convex subproblems solved.
        norm_error: max over nodes of ``| ‖q_k‖ − 1 |`` of the last subproblem's
            quaternions before renormalisation.
        terminal_error_rad: angle between r1 and the exact integration of ``w``
            from r0 (``R ← R · Exp(w_k h)``), rad.
    """

    t_s: FloatArray
    q: FloatArray
    w: FloatArray
    status: str
    converged: bool
    iterations: int
    norm_error: float
    terminal_error_rad: float
    _path: _NodePath = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_path", _NodePath.through(np.asarray(self.t_s, float), self.q))

    def at(self, t: float) -> PlanSample:
        """Desired ``(R_ref_body, ω_body rad/s, ω̇_body rad/s²)`` at time t (s)."""
        return self._path.sample(self.w, t)

    def at_quat(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """As :meth:`at` with the attitude as a quaternion (4,), scalar last."""
        out: tuple[FloatArray, FloatArray, FloatArray] = self._path.sample(self.w, t, True)
        return out

    def nodes(self) -> PlanNodes:
        """The plan as its node path (:data:`PlanNodes`)."""
        return self._path.t_s, self._path.q, self._path.phi, self.w


# ---------------------------------------------------------------------------
# quaternion matrices for the SCP (scalar-last, Hamilton): p ⊗ q = L(p) q = R(q) p


def _quat_left(p: FloatArray) -> FloatArray:
    """L(p), shape (..., 4, 4), with ``p ⊗ q = L(p) q``: [[p_w I + [p_v]×, p_v], [−p_vᵀ, p_w]]."""
    x, y, z, w = np.moveaxis(np.asarray(p), -1, 0)
    return np.stack(
        [
            np.stack([w, -z, y, x], axis=-1),
            np.stack([z, w, -x, y], axis=-1),
            np.stack([-y, x, w, z], axis=-1),
            np.stack([-x, -y, -z, w], axis=-1),
        ],
        axis=-2,
    )


def _quat_right(q: FloatArray) -> FloatArray:
    """R(q), shape (..., 4, 4), with ``p ⊗ q = R(q) p``: [[q_w I − [q_v]×, q_v], [−q_vᵀ, q_w]]."""
    x, y, z, w = np.moveaxis(np.asarray(q), -1, 0)
    return np.stack(
        [
            np.stack([w, z, -y, x], axis=-1),
            np.stack([-z, w, x, y], axis=-1),
            np.stack([y, -x, w, z], axis=-1),
            np.stack([-x, -y, -z, w], axis=-1),
        ],
        axis=-2,
    )


def _exp_and_jacobian(w: FloatArray, h: float) -> tuple[FloatArray, FloatArray]:
    """``E(ω) = Exp(ω h)`` (N, 4) and its Jacobian ``∂E/∂ω`` (N, 4, 3) for rates w (N, 3).

    With ``a = |ω|`` and ``f(a) = sin(a h/2)/a``: ``E = [f ω, cos(a h/2)]``,
    ``∂E_v/∂ω = f I + (f'(a)/a) ω ωᵀ`` with
    ``f'(a)/a = ((h/2) cos(a h/2) − f)/a²`` and ``∂E_w/∂ω = −(h/2) f ωᵀ``.  For
    ``a h < 1e-3`` the Taylor series ``f ≈ h/2 − (h/2)³ a²/6``,
    ``f'(a)/a ≈ −(h/2)³/3`` is used (relative error below 1e-13).
    """
    a = np.linalg.norm(w, axis=-1)
    c = 0.5 * h
    small = a * h < 1e-3
    a_safe = np.where(small, 1.0, a)
    f = np.where(small, c - c**3 * a * a / 6.0, np.sin(a_safe * c) / a_safe)
    g = np.where(small, -(c**3) / 3.0, (c * np.cos(a_safe * c) - f) / a_safe**2)
    e = np.concatenate([f[:, None] * w, np.cos(a * c)[:, None]], axis=-1)
    jac = np.empty(w.shape[:-1] + (4, 3))
    jac[:, :3, :] = f[:, None, None] * np.eye(3) + g[:, None, None] * w[:, :, None] * w[:, None, :]
    jac[:, 3, :] = -c * f[:, None] * w
    return e, jac


def _rollout(q0: FloatArray, w: FloatArray, h: float) -> FloatArray:
    """Exact integration of piecewise-constant body rates, ``q_{k+1} = q_k ⊗ Exp(w_k h)``.

    Returns the N+1 node quaternions (scalar-last, sign-continuous from ``q0``).
    """
    e, _ = _exp_and_jacobian(w, h)
    right = _quat_right(e)
    q = np.empty((w.shape[0] + 1, 4))
    q[0] = q0
    for k in range(w.shape[0]):
        q[k + 1] = right[k] @ q[k]
    return q


# ---------------------------------------------------------------------------
# SCP slew

_SCP_EPS_SMALL = 1e-2  # weight of the small Σ‖u‖² term relative to the smoothness term
_SCP_PROX_WEIGHT = 1e-2  # proximal (soft trust-region) weight on the step
_SCP_STEP_TOL = 1e-7  # convergence: max change of q or ω/w_max between iterates
_SCP_TERMINAL_TOL_RAD = 1e-5  # exact-kinematics landing tolerance for "solved"
# No Ruiz scaling: the variables are already O(1) (unit quaternions, u = ω/w_max) and
# OSQP's equilibration of the orthogonal kinematics blocks slowed ADMM ~30-fold here.
_OSQP_SETTINGS: tuple[tuple[str, object], ...] = (
    ("verbose", False), ("eps_abs", 1e-6), ("eps_rel", 1e-6), ("eps_prim_inf", 1e-6),
    ("max_iter", 20000), ("scaling", 0), ("polishing", True), ("warm_starting", True),
    ("adaptive_rho_interval", 25), ("check_termination", 10),
)


def _scp_cost(n: int) -> sp.csc_matrix:
    """Upper triangle of the OSQP Hessian P (cost ``½ zᵀ P z + cᵀ z``),
    z = [q_0..q_N, u_0..u_{N−1}].

    Cost ``N Σ‖u_{k+1} − u_k‖² + (ε/N) Σ‖u_k‖² + ρ (‖q − q̄‖² + ‖u − ū‖²)``; the first
    two terms are grid-independent approximations of ``T ∫|u̇|² dt`` and
    ``(1/T) ∫|u|² dt``; the linear part of the proximal term goes into c.
    """
    d = sp.kron(sp.eye(n - 1, n, k=1) - sp.eye(n - 1, n), sp.eye(3))
    p_u = 2.0 * (n * (d.T @ d) + (_SCP_EPS_SMALL / n + _SCP_PROX_WEIGHT) * sp.eye(3 * n))
    p_q = 2.0 * _SCP_PROX_WEIGHT * sp.eye(4 * (n + 1))
    return sp.triu(sp.block_diag([p_q, p_u], format="csc"), format="csc")


def _blocks(r0: FloatArray, c0: FloatArray, nr: int, nc: int) -> tuple[FloatArray, FloatArray]:
    """(row, col) of dense nr×nc blocks at corners (r0[k], c0[k]), block-major, row-major."""
    rr = r0[:, None, None] + np.arange(nr)[None, :, None] + np.zeros((1, 1, nc), dtype=np.int64)
    cc = c0[:, None, None] + np.arange(nc)[None, None, :] + np.zeros((1, nr, 1), dtype=np.int64)
    return rr.ravel(), cc.ravel()


def _scp_pattern(n: int) -> tuple[FloatArray, FloatArray, int]:
    """(row, col) of every constraint-matrix entry, in the order _scp_values fills them.

    Rows: dynamics (4N), interior norm (N−1), ``q_0`` (4), terminal attitude (3),
    rate box (3N).  Columns: q_0..q_N (4 each), then u_0..u_{N−1} (3 each).
    Dynamics row block k: ``q_{k+1} − R_k q_k − B_k u_k = −B_k ū_k``.
    """
    iu = 4 * (n + 1)
    k = np.arange(n)
    r_dyn = 4 * k
    kk = np.arange(1, n)
    parts = [
        (np.arange(4 * n), np.arange(4, 4 * (n + 1))),  # +I on q_{k+1}
        _blocks(r_dyn, 4 * k, 4, 4),  # −R_k on q_k
        _blocks(r_dyn, iu + 3 * k, 4, 3),  # −B_k on u_k
        _blocks(4 * n + kk - 1, 4 * kk, 1, 4),  # q̄_kᵀ q_k = 1
        (5 * n - 1 + np.arange(4), np.arange(4)),  # q_0 = r0
        _blocks(np.array([5 * n + 3]), np.array([4 * n]), 3, 4),  # vec(q1* ⊗ q_N) = 0
        (5 * n + 6 + np.arange(3 * n), iu + np.arange(3 * n)),  # rate box
    ]
    rows = np.concatenate([p[0] for p in parts])
    cols = np.concatenate([p[1] for p in parts])
    return rows, cols, 8 * n + 6


def _scp_values(
    q_ref: FloatArray, u_ref: FloatArray, q1: FloatArray, h: float, w_max: float
) -> tuple[FloatArray, FloatArray]:
    """Constraint-matrix values (pattern order) and the dynamics right-hand side.

    Linearisation of ``q_{k+1} = q_k ⊗ Exp(ω_k h)`` about ``(q̄_k, ω̄_k)``:
    ``q_{k+1} ≈ R(Ē_k) q_k + L(q̄_k) J_E(ω̄_k) (ω_k − ω̄_k)`` (the constant terms
    cancel because ``q̄ ⊗ Ē = R(Ē) q̄``).
    """
    n = u_ref.shape[0]
    e, jac = _exp_and_jacobian(u_ref * w_max, h)
    b = np.einsum("kij,kjl->kil", _quat_left(q_ref[:-1]), jac) * w_max
    rhs = -np.einsum("kij,kj->ki", b, u_ref).ravel()
    q1_conj = np.array([-q1[0], -q1[1], -q1[2], q1[3]])
    vals = [
        np.ones(4 * n),
        -_quat_right(e).ravel(),
        -b.ravel(),
        q_ref[1:n].ravel(),
        np.ones(4),
        _quat_left(q1_conj)[:3, :].ravel(),
        np.ones(3 * n),
    ]
    return np.concatenate(vals), rhs


class _SlewSubproblem:
    """The convex subproblem of :func:`scp_slew` as OSQP holds it over the iterations: the cost
    (:func:`_scp_cost`), the constraint sparsity (:func:`_scp_pattern`) and the fixed bounds
    (interior norms, ``q_0``, the rate box and the boundary rates ``fixed_rates``, scaled, by
    interval) are set once; each :meth:`solve` linearises about its iterate (:func:`_scp_values`),
    updates the matrix values and vectors and warm-starts from the previous solution."""

    def __init__(self, n: int, q0: FloatArray, fixed_rates: dict[int, FloatArray]) -> None:
        self._p_mat = _scp_cost(n)
        rows, cols, m = _scp_pattern(n)
        # CSC structure once; `perm` maps pattern order to CSC data order
        probe = sp.coo_matrix((np.arange(1.0, rows.size + 1.0), (rows, cols)),
                              shape=(m, 4 * (n + 1) + 3 * n))
        self._probe = probe = probe.tocsc()
        if probe.nnz != rows.size:
            raise RuntimeError("internal error: duplicate entries in the SCP constraint pattern")
        self._perm = probe.data.astype(np.int64) - 1
        self._lo, self._hi = lo, hi = np.zeros(m), np.zeros(m)
        self._r_norm, r_q0, r_box = 4 * n, 5 * n - 1, 5 * n + 6
        lo[self._r_norm:r_q0] = hi[self._r_norm:r_q0] = 1.0
        lo[r_q0:r_q0 + 4] = hi[r_q0:r_q0 + 4] = q0
        lo[r_box:] = -1.0
        hi[r_box:] = 1.0
        for k, ub in fixed_rates.items():
            lo[r_box + 3 * k:r_box + 3 * k + 3] = hi[r_box + 3 * k:r_box + 3 * k + 3] = ub
        self._solver: osqp.OSQP | None = None

    def solve(self, q_ref: FloatArray, u_ref: FloatArray, q1: FloatArray, h: float,
              w_max: float) -> tuple[str, FloatArray]:
        """Solve the subproblem linearised about ``(q_ref, u_ref)`` (landing on ``q1``, intervals
        of ``h`` s, rate limit ``w_max`` rad/s); return OSQP's status and its solution z."""
        lo, hi, r_norm = self._lo, self._hi, self._r_norm
        vals, rhs = _scp_values(q_ref, u_ref, q1, h, w_max)
        lo[:r_norm] = hi[:r_norm] = rhs
        c = -2.0 * _SCP_PROX_WEIGHT * np.concatenate([q_ref.ravel(), u_ref.ravel()])
        if self._solver is None:
            probe = self._probe
            a_mat = sp.csc_matrix((vals[self._perm], probe.indices, probe.indptr),
                                  shape=probe.shape)
            self._solver = osqp.OSQP()
            self._solver.setup(self._p_mat, c, a_mat, lo, hi, **dict(_OSQP_SETTINGS))
        else:
            self._solver.update(q=c, l=lo, u=hi, Ax=vals[self._perm])
        res = self._solver.solve(raise_error=False)
        return str(res.info.status), np.asarray(res.x, dtype=float)


def _slew_inputs(
    r0: Rotation, r1: Rotation, duration_s: float, n_nodes: int, w_max_radps: float,
    w0: npt.ArrayLike | None, w1: npt.ArrayLike | None, max_iters: int, t0_s: float,
) -> tuple[int, float, float, float, dict[int, FloatArray]]:
    """:func:`scp_slew`'s arguments checked: (intervals N, duration s, rate limit rad/s, start
    time s, the boundary rates given by interval, scaled by the limit).  Raises ValueError."""
    _single_rotation("r0", r0)
    _single_rotation("r1", r1)
    duration = _positive("duration_s", duration_s)
    w_max = _positive("w_max_radps", w_max_radps)
    t0 = _finite("t0_s", t0_s)
    for name, value in (("n_nodes", n_nodes), ("max_iters", max_iters)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise ValueError(f"{name} must be an integer, got {value!r}")
    if n_nodes < 3 or max_iters < 1:
        raise ValueError(f"need n_nodes >= 3 and max_iters >= 1, got {n_nodes}, {max_iters}")
    n = int(n_nodes) - 1
    fixed_rates: dict[int, FloatArray] = {}
    for name, value, k in (("w0", w0, 0), ("w1", w1, n - 1)):
        if value is not None:
            fixed_rates[k] = finite_array(name, value, (3,)) / w_max
    return n, duration, w_max, t0, fixed_rates


def scp_slew(
    r0: Rotation,
    r1: Rotation,
    duration_s: float,
    n_nodes: int,
    w_max_radps: float,
    *,
    w0: npt.ArrayLike | None = None,
    w1: npt.ArrayLike | None = None,
    max_iters: int = 10,
    t0_s: float = 0.0,
) -> SlewPlan:
    """Rate-limited smooth slew from r0 to r1 by sequential convex programming (SCP).

    Decision variables: quaternions ``q_k`` (4) at ``n_nodes = N+1`` equally spaced
    nodes and body rates ``ω_k`` (3) on the N intervals (``h = duration/N``),
    scaled as ``u_k = ω_k / w_max``.  Each iteration solves the convex QP

    * kinematics ``q_{k+1} = q_k ⊗ Exp(ω_k h)`` (exact for piecewise-constant
      rates) linearised about the previous iterate ``(q̄, ω̄)``, where ``q̄`` is the
      exact integration of the previous rates ``ω̄`` from r0 (a dynamically
      consistent trajectory); the first iterate is the slerp plan;
    * the linearised unit-norm constraint ``q̄_kᵀ q_k = 1`` at the interior nodes
      (the paper's "norm constraint on the quaternions");
      ``‖q_k‖² = 1 + ‖q_k − q̄_k‖²`` then deviates from 1 only to second order.
      About a consistent ``q̄`` these rows are implied by the linearised
      kinematics (OSQP copes with the redundancy); linearising about the
      renormalised QP quaternions instead makes the two sets conflict, which
      stalled ADMM whenever the rate limit was active;
    * boundary attitudes: ``q_0 = r0`` and ``q_N ∥ q1`` written as
      ``vec(q1* ⊗ q_N) = 0`` (3 equations), with the sign of q1 chosen for the
      short way (``q0ᵀ q1 ≥ 0``).  The fourth terminal equation (the norm) is left
      to the kinematics: the linearised exact kinematics conserves
      ``(q̄_k ⊗ Ē_k)ᵀ q_{k+1} = q̄_kᵀ q_k``, so imposing ``q_N = q1`` in full would
      be infeasible except at the fixed point (this is why SCvx-type methods add a
      virtual control; fixing only the attitude avoids it).  After
      renormalisation ``q_N = q1`` exactly;
    * optional boundary rates ``ω_0 = w0``, ``ω_{N−1} = w1``;
    * per-axis rate limit ``|ω_k,j| ≤ w_max``;
    * cost ``N Σ‖u_{k+1} − u_k‖²`` (smoothness ~ torque effort)
      ``+ (0.01/N) Σ‖u_k‖²`` and a proximal term ``0.01 (‖q − q̄‖² + ‖u − ū‖²)``
      (a soft trust region, zero at the fixed point; Mao, Szmuk & Açıkmeşe,
      "Successive convexification of non-convex optimal control problems", CDC
      2016; Malyuta et al., "Convex optimization for trajectory generation",
      IEEE CSM 42(5), 2022).

    OSQP (Stellato et al., Math. Prog. Comp. 12, 2020) is set up once, at the first
    iteration; later iterations update the matrix values and vectors (same sparsity)
    and warm-start from the previous solution.  Each solution's quaternions,
    renormalised, are the plan's nodes; its rates (clipped to the box, which OSQP
    meets only to its tolerance) give the next linearisation point; iteration
    stops when the largest change of ``q`` or ``u`` is below 1e-7.  A subproblem that OSQP
    proves primal infeasible (the rate box cannot reach r1 in time) ends the
    iteration with status ``"infeasible"``; so does a boundary rate outside the box
    (no subproblem is solved then).

    Args:
        r0: start attitude ``R_ref_body``.
        r1: end attitude ``R_ref_body`` (either quaternion sign).
        duration_s: slew duration, s (> 0).
        n_nodes: number of quaternion nodes N+1 (>= 3).
        w_max_radps: per-axis body-rate limit, rad/s (> 0).
        w0: body rate on the first interval, rad/s (3,), or None (free).
        w1: body rate on the last interval, rad/s (3,), or None (free).
        max_iters: maximum number of convex subproblems (>= 1).
        t0_s: time of the first node, s.

    Returns:
        The :class:`SlewPlan` (check ``status``).  On ``"infeasible"`` or
        ``"solver_error"`` it holds the last good iterate (the slerp plan if none).

    Raises:
        ValueError: non-finite or ill-shaped inputs, ``n_nodes < 3``.  A boundary
            rate outside the rate limit is not an error: the plan comes back
            ``"infeasible"`` (e.g. when ``w0`` is a measured rate above the limit).
    """
    n, duration, w_max, t0, fixed_rates = _slew_inputs(
        r0, r1, duration_s, n_nodes, w_max_radps, w0, w1, max_iters, t0_s)
    # a boundary rate outside the box makes every subproblem infeasible
    rates_ok = all(bool(np.all(np.abs(u) <= 1.0)) for u in fixed_rates.values())

    h = duration / n
    iu = 4 * (n + 1)
    t_nodes = t0 + h * np.arange(n + 1)
    q0 = r0.as_quat()
    q1 = r1.as_quat()
    if float(q0 @ q1) < 0.0:
        q1 = -q1

    # initial guess: the slerp plan (constant rate; its nodes are the exact rollout)
    u_ref = np.tile(slerp_plan(r0, r1, t_nodes[0], t_nodes[-1]).at(t0)[1] / w_max, (n, 1))
    q_ref = _rollout(q0, u_ref * w_max, h)

    subproblem = _SlewSubproblem(n, q0, fixed_rates)
    q_plan = q_ref
    status = ""
    converged = False
    iterations = 0
    norm_error = 0.0
    if not rates_ok:
        status = "infeasible"
    for _ in range(int(max_iters) if rates_ok else 0):
        osqp_status, z = subproblem.solve(q_ref, u_ref, q1, h, w_max)
        if osqp_status.startswith("primal infeasible"):
            status = "infeasible"
            break
        if osqp_status not in ("solved", "solved inaccurate") or not np.all(np.isfinite(z)):
            status = "solver_error"
            break
        iterations += 1
        q_sol = z[:iu].reshape(n + 1, 4)
        norms = np.linalg.norm(q_sol, axis=1)
        norm_error = float(np.max(np.abs(norms - 1.0)))
        q_plan = q_sol / norms[:, None]
        # OSQP meets the box to its tolerance only
        u_new = np.clip(z[iu:].reshape(n, 3), -1.0, 1.0)
        step = max(float(np.max(np.abs(q_plan - q_ref))), float(np.max(np.abs(u_new - u_ref))))
        u_ref = u_new
        q_ref = _rollout(q0, u_ref * w_max, h)
        if step < _SCP_STEP_TOL:
            converged = True
            break

    w = u_ref * w_max
    terminal = float((Rotation.from_quat(q_ref[-1]).inv() * r1).magnitude())  # q_ref: rollout of w
    if not status:
        status = "solved" if terminal <= _SCP_TERMINAL_TOL_RAD else "not_converged"
    return SlewPlan(
        t_s=t_nodes, q=q_plan, w=w, status=status, converged=converged, iterations=iterations,
        norm_error=norm_error, terminal_error_rad=terminal,
    )
