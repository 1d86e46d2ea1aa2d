"""Fuel-optimal relative-orbit transfer by sequential convex programming (SCP) with OSQP.

Problem (paper Sec. II.B: an optimal control problem with an L1 fuel cost and safety and
energy-matching constraints, solved by SCP).  Over ``N`` intervals of length ``h = T / N`` the
acceleration ``u_k`` (m/s^2, LVLH) is held constant (zero-order hold) and the HCW dynamics are
discretised exactly (``hcw.discretize``)::

    minimise    sum_k sum_j |u_kj| h                       (Delta-v of per-axis thrusters, m/s)
    subject to  x_{k+1} = Ad x_k + Bd u_k,  x_0 = x0,  x_N = xf
                |u_kj| <= u_max
                |r(t)| >= d_min  for all t in [0, T]      (keep-out sphere about the target)

The terminal state ``xf`` is supplied by the caller (the assigned PRO's state at arrival, energy
matched with ``gnc.pro.energy_matched_state`` for the nonlinear world).  The L1 cost is
written with slacks ``s >= u``, ``s >= -u``.  The keep-out constraint is non-convex; about the
previous iterate ``r_bar`` it is replaced by the half-space ``r_hat^T r >= d_min`` with
``r_hat = r_bar / |r_bar|``, which lies outside the sphere (``|r| >= r_hat^T r``), so every
point meeting it is safe.  The previous iterate satisfies its own linearisation
(``r_hat^T r_bar = |r_bar|``), so once an iterate is safe the next cost is no higher (the
convex-concave procedure; Lipp & Boyd, Optim. Eng. 17, 2016).  A proximal term
``w/2 |z - z_ref|^2`` on the scaled states and inputs acts as a soft trust region: it keeps
successive iterates close (and the subproblems strongly convex in the states and inputs) and
vanishes at a fixed point, so it does not change what the iteration converges to.
The half-spaces are imposed at the nodes, at fixed points inside every interval
(``r(t_k + tau) = Phi_r(tau) x_k + Gamma_r(tau) u_k``, affine in ``x_k, u_k``) and at every
point where a dense check of the exact inter-node propagation (with Brent refinement of each
local minimum of ``|r|``) found the previous plan inside the sphere.  The loop stops when the
trajectory and the cost no longer change and the dense check passes, so a returned
``"solved"`` plan satisfies ``|r| >= d_min`` at every node and along the exact ZOH propagation.

Degenerate linearisation: the first reference (the plan without keep-out) may pass through the
sphere, even through its centre (e.g. a cross-track transfer through the target), where
``r_hat`` is undefined or flips sign.  For every run of reference points inside the sphere the
points are lifted onto a detour: with ``c`` the path direction at closest approach and ``p`` the
side of the miss (or a fixed perpendicular when the path hits the centre), a point at ``s`` along
``c`` is moved to at least ``sqrt(d_min^2 - s^2)`` along ``p``, so the half-spaces turn smoothly
from ``-c`` through ``p`` to ``+c`` and the first convex subproblem routes around the sphere.

Solver: OSQP (Stellato et al., Math. Prog. Comp. 12, 2020).  Inputs are scaled by ``u_max`` and
states by a length and a speed (REFERENCE.md: unscaled it stalls); the dynamics/boundary rows and
the keep-out rows carry row weights (see :class:`ScpSettings`); each subproblem is warm-started
from the previous one and solved along a short tolerance ladder with polishing.  ADMM reaches
only moderate accuracy on these LPs, so every answer is post-processed into an exactly feasible
plan: the inputs are clipped to ``u_max``, the small terminal residual is removed by a
minimum-norm input correction, the nodes are re-propagated exactly, and the keep-out is
re-checked densely (the half-spaces carry a margin for the solver residual and for the chord
sagitta between constraint points).  Failures are statuses, never exceptions: see
:class:`TransferPlan` and the ``STATUS_*`` constants.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
import osqp
import scipy.sparse as sp
from scipy.optimize import minimize_scalar

from gnc import hcw
from gnc.hcw import zoh_matrices

__all__ = [
    "STATUS_INFEASIBLE_ENDPOINT",
    "STATUS_INFEASIBLE_KEEP_OUT",
    "STATUS_INFEASIBLE_THRUST",
    "STATUS_KEEP_OUT_VIOLATED",
    "STATUS_MAX_ITERATIONS",
    "STATUS_SOLVED",
    "STATUS_SOLVER_FAILED",
    "ScpSettings",
    "TransferPlan",
    "plan_transfer",
    "zoh_matrices",
]

FloatArray = npt.NDArray[np.float64]

STATUS_SOLVED = "solved"
"""Converged; dynamics, thrust limit, terminal state and keep-out (dense check) all met."""
STATUS_MAX_ITERATIONS = "max_iterations"
"""SCP iteration cap reached; the plan (the cheapest safe iterate) meets every constraint but
the cost or trajectory had not settled."""
STATUS_KEEP_OUT_VIOLATED = "keep_out_violated"
"""SCP iteration cap reached with the exact propagation still inside the keep-out sphere."""
STATUS_INFEASIBLE_THRUST = "infeasible_thrust_limit"
"""The terminal state cannot be reached in the duration with |u_j| <= u_max (even ignoring the
keep-out): a longer duration or a larger thrust limit is needed."""
STATUS_INFEASIBLE_KEEP_OUT = "infeasible_keep_out"
"""A convexified keep-out subproblem was infeasible (thrust too small to go around)."""
STATUS_INFEASIBLE_ENDPOINT = "infeasible_endpoint_in_keep_out"
"""The initial or terminal position lies inside the keep-out sphere."""
STATUS_SOLVER_FAILED = "solver_failed"
"""OSQP returned no usable iterate (e.g. a non-finite one, or a status other than solved /
inaccurate / iteration or time cap / infeasible), or the cleaned-up answer still missed the
terminal state; the detail follows after a colon."""

_DEGENERATE_REL = 1e-9
"""A miss distance below this fraction of d_min counts as a hit on the centre (detours)."""


@dataclass(frozen=True)
class ScpSettings:
    """Tuning of :func:`plan_transfer` (defaults suit 10-1000 m transfers in LEO).

    Attributes:
        sub_points: keep-out points imposed inside every interval (besides the nodes).
        check_points: samples per interval of the dense exact check (each local minimum of
            ``|r|`` found there is then refined by Brent search).
        keep_out_margin_m: the half-spaces use ``d_min + margin`` (plus the chord margin of
            ``_margins``) so that the solver's residual on them (measured up to 5 mm at
            eps 1e-4 on 50 m transfers) does not put the plan inside ``d_min``, m.
        prox_state_weight: weight of the proximal term ``w/2 |X - X_ref|^2`` on the scaled node
            states in the keep-out subproblems (a soft trust region; it vanishes at a fixed
            point, so it does not change what the SCP converges to).
        prox_input_weight: the same on the scaled inputs ``u / u_max``.
        equality_row_weight: factor on the dynamics and boundary rows, and
        keep_out_row_weight: on the keep-out rows of the OSQP matrix.  OSQP's equilibration
            leaves the relative weight of row groups partly in place; weighting the few keep-out
            rows up cut the ADMM iterations 3-5x and the terminal/keep-out residuals 5-10x on
            the test transfers (an ADMM step size per row group, in effect).
        tol_cost_rel: SCP stops when the relative change of the Delta-v is below this...
        tol_cost_abs_mps: ...or its absolute change is below this, m/s.
        terminal_tol_m: accepted terminal position error of the propagated plan, m; the
            velocity error is held to the same fraction of the speed scale (about
            ``2 * distance / T``).  A larger error is reported as ``solver_failed``.
        eps_ladder: OSQP tolerances (absolute = relative, scaled problem) tried in turn, each
            continuing from the last iterate, until polishing succeeds (the polished answer is
            the exact LP vertex); if none polishes, the last solved ADMM answer is used
            (feasibility is restored by the exact propagation and terminal clean-up anyway).
            Used for the first subproblem (no keep-out), which polishes by 1e-5 as a rule.
        eps_ladder_keep_out: the same for the keep-out subproblems, which rarely polish: the
            third stage doubled the planning time for 0.03 % of fuel on random transfers.
        max_osqp_iter: OSQP iteration cap per stage of the ladder.
        time_limit_s: OSQP run-time limit per subproblem, s (0 disables it).
        polish: OSQP solution polishing (an active-set refinement, exact for LPs).
    """

    sub_points: int = 2
    check_points: int = 20
    keep_out_margin_m: float = 1e-2
    prox_state_weight: float = 0.01
    prox_input_weight: float = 0.001
    equality_row_weight: float = 10.0
    keep_out_row_weight: float = 300.0
    tol_cost_rel: float = 1e-3
    tol_cost_abs_mps: float = 1e-9
    terminal_tol_m: float = 1e-7
    eps_ladder: tuple[float, ...] = (1e-3, 1e-4, 1e-5)
    eps_ladder_keep_out: tuple[float, ...] = (1e-3, 1e-4)
    max_osqp_iter: int = 4000
    time_limit_s: float = 0.0
    polish: bool = True


@dataclass(frozen=True)
class TransferPlan:
    """A planned transfer.  Times are relative to departure.

    Attributes:
        t_s: node times ``k h``, shape (N+1,), s.
        x: node states (exact ZOH propagation of ``u`` from ``x0``), shape (N+1, 6), m, m/s.
        u: accelerations held on each interval, shape (N, 3), m/s^2 (LVLH).
        dv_mps: L1 fuel ``sum |u_kj| h``, m/s.
        iterations: convex subproblems solved.
        converged: True only for status ``"solved"``: use the plan only then.
        status: one of the ``STATUS_*`` strings (``solver_failed`` carries OSQP's status).
        min_range_m: minimum of ``|r(t)|`` over the exact propagation (dense check), m.
        solve_time_s: wall time of the whole planning call, s.
        n_rad_s: mean motion of the model, rad/s (for :meth:`state_at`).
        admm_iterations: OSQP iterations summed over all subproblems.
        lp_size: ``(variables, constraints, nonzeros)`` of the last subproblem.
    When no subproblem produced a usable solution, ``u`` is zero and ``x`` the coasting
    trajectory from ``x0`` (so the arrays are always well-formed).
    """

    t_s: FloatArray
    x: FloatArray
    u: FloatArray
    dv_mps: float
    iterations: int
    converged: bool
    status: str
    min_range_m: float
    solve_time_s: float
    n_rad_s: float = field(default=0.0)
    admm_iterations: int = 0
    lp_size: tuple[int, int, int] = (0, 0, 0)

    def states_at(self, t: npt.ArrayLike) -> FloatArray:
        """Exact ZOH-propagated states at times ``t`` in ``[0, T]`` (s); shape (T, 6).

        Raises:
            ValueError: a time outside the plan (by more than 1e-9 T) or not finite.
        """
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        duration = float(self.t_s[-1])
        slack = 1e-9 * duration
        if tt.ndim != 1 or not np.all(np.isfinite(tt)) or np.any(tt < -slack) or np.any(
                tt > duration + slack):
            raise ValueError(f"times must lie in [0, {duration}] s")
        h = float(self.t_s[1] - self.t_s[0])
        k = np.clip(np.floor(tt / h).astype(int), 0, len(self.u) - 1)
        tau = np.clip(tt - k * h, 0.0, h)
        phi, gam = zoh_matrices(self.n_rad_s, tau)
        return np.einsum("tij,tj->ti", phi, self.x[k]) + np.einsum("tij,tj->ti", gam, self.u[k])

    def state_at(self, t: float) -> FloatArray:
        """Exact ZOH-propagated state at time ``t`` in ``[0, T]`` (s); shape (6,)."""
        return self.states_at(np.array([t]))[0]


# --------------------------------------------------------------------------------------------
# problem data


@dataclass(frozen=True)
class _Problem:
    """Fixed data of one planning call (SI units) and the scaling of the OSQP variables."""

    n: float
    x0: FloatArray
    xf: FloatArray
    h: float
    n_int: int
    u_max: float
    d_min: float | None
    ad: FloatArray
    bd: FloatArray
    length: float  # position scale, m
    speed: float  # velocity scale, m/s

    @property
    def dscale(self) -> FloatArray:
        return np.array([self.length] * 3 + [self.speed] * 3)

    @property
    def n_x(self) -> int:
        return 6 * (self.n_int + 1)

    @property
    def n_u(self) -> int:
        return 3 * self.n_int


def _validate(n: float, x0: npt.ArrayLike, xf: npt.ArrayLike, duration_s: float,
              n_intervals: int, u_max_mps2: float, d_min_m: float | None,
              max_iters: int) -> tuple[FloatArray, FloatArray]:
    a0 = np.asarray(x0, dtype=float)
    af = np.asarray(xf, dtype=float)
    for name, arr in (("x0", a0), ("xf", af)):
        if arr.shape != (6,) or not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} must be a finite (6,) state, got {arr!r}")
    checks = (
        (n > 0.0 and math.isfinite(n), f"mean motion must be positive, got {n!r}"),
        (duration_s > 0.0 and math.isfinite(duration_s), f"bad duration {duration_s!r} s"),
        (isinstance(n_intervals, (int, np.integer)) and n_intervals >= 1,
         f"n_intervals must be an integer >= 1, got {n_intervals!r}"),
        (u_max_mps2 > 0.0 and math.isfinite(u_max_mps2), f"bad u_max {u_max_mps2!r} m/s^2"),
        (d_min_m is None or (d_min_m > 0.0 and math.isfinite(d_min_m)),
         f"d_min must be None or positive, got {d_min_m!r} m"),
        (isinstance(max_iters, (int, np.integer)) and max_iters >= 1,
         f"max_iters must be an integer >= 1, got {max_iters!r}"),
    )
    for ok, msg in checks:
        if not ok:
            raise ValueError(msg)
    return a0, af


def _make_problem(n: float, x0: FloatArray, xf: FloatArray, duration: float, n_int: int,
                  u_max: float, d_min: float | None) -> _Problem:
    h = duration / n_int
    ad, bd = hcw.discretize(n, h)
    length = max(float(np.linalg.norm(x0[:3])), float(np.linalg.norm(xf[:3])), d_min or 0.0, 1.0)
    speed = max(2.0 * length / duration, float(np.linalg.norm(x0[3:])),
                float(np.linalg.norm(xf[3:])), u_max * h)
    return _Problem(n, x0, xf, h, n_int, u_max, d_min, ad, bd, length, speed)


# --------------------------------------------------------------------------------------------
# trajectories


def _propagate_nodes(pb: _Problem, u: FloatArray) -> FloatArray:
    """Node states from x0 under the held inputs u (N, 3): exact ZOH recursion."""
    x = np.empty((pb.n_int + 1, 6))
    x[0] = pb.x0
    for k in range(pb.n_int):
        x[k + 1] = pb.ad @ x[k] + pb.bd @ u[k]
    return x


def _states_in_intervals(pb: _Problem, x: FloatArray, u: FloatArray, k: npt.NDArray[np.int_],
                         tau: FloatArray) -> FloatArray:
    """States at offsets tau (s) inside intervals k, shape (P, 6)."""
    phi, gam = zoh_matrices(pb.n, tau)
    return np.einsum("pij,pj->pi", phi, x[k]) + np.einsum("pij,pj->pi", gam, u[k])


def _dense_check(pb: _Problem, x: FloatArray, u: FloatArray, points: int,
                 threshold: float | None) -> tuple[float, list[tuple[int, float]]]:
    """Minimum range along the exact propagation and the local minima below ``threshold``.

    |r| is sampled ``points`` times per interval (plus the final node); every sampled local
    minimum is refined by bounded Brent search over its two neighbouring samples.

    Returns:
        ``(min_range_m, violations)`` with violations as ``(interval, tau_s)`` of the refined
        minima that are below ``threshold`` (none when threshold is None).
    """
    g = np.arange(points) * (pb.h / points)
    k_all = np.repeat(np.arange(pb.n_int), points)
    tau_all = np.tile(g, pb.n_int)
    r = _states_in_intervals(pb, x, u, k_all, tau_all)[:, :3]
    d = np.append(np.linalg.norm(r, axis=1), np.linalg.norm(x[-1, :3]))
    t_grid = np.append(k_all * pb.h + tau_all, pb.n_int * pb.h)
    duration = pb.n_int * pb.h

    def dist(t: float) -> float:
        kk = min(int(t // pb.h), pb.n_int - 1)
        tau = min(max(t - kk * pb.h, 0.0), pb.h)
        phi, gam = zoh_matrices(pb.n, tau)
        return float(np.linalg.norm((phi @ x[kk] + gam @ u[kk])[:3]))

    best = float(np.min(d))
    violations: list[tuple[int, float]] = []
    # strict on the left so that a constant stretch (a hold point) yields no candidates
    interior = np.flatnonzero((d[1:-1] < d[:-2]) & (d[1:-1] <= d[2:])) + 1
    # refine only minima that could matter: all if no threshold, else those near it
    limit = np.inf if threshold is None else threshold * 1.05 + 1e-9
    for i in interior[d[interior] < limit]:
        lo, hi = t_grid[i - 1], t_grid[i + 1]
        res = minimize_scalar(dist, bounds=(lo, hi), method="bounded",
                              options={"xatol": 1e-9 * duration})
        t_min, d_min = (float(res.x), float(res.fun)) if res.fun < d[i] else (t_grid[i], d[i])
        best = min(best, d_min)
        if threshold is not None and d_min < threshold:
            kk = min(int(t_min // pb.h), pb.n_int - 1)
            violations.append((kk, t_min - kk * pb.h))
    if threshold is not None and not violations and float(np.min(d)) < threshold:
        i = int(np.argmin(d))  # inside on a flat stretch (no strict local minimum): flag it
        kk = min(int(t_grid[i] // pb.h), pb.n_int - 1)
        violations.append((kk, float(t_grid[i]) - kk * pb.h))
    return best, violations


# --------------------------------------------------------------------------------------------
# keep-out linearisation


def _orthogonal_unit(c: FloatArray) -> FloatArray:
    """A unit vector perpendicular to unit c: the LVLH axis least aligned with c, orthogonalised
    (x radial first on ties, which routes a centre-crossing path radially)."""
    axis = np.eye(3)[int(np.argmin(np.abs(c)))]
    p = axis - (axis @ c) * c
    return p / np.linalg.norm(p)


def _keep_out_normals(r: FloatArray, v: FloatArray, d_min: float) -> FloatArray:
    """Unit normals r_hat of the linearised keep-out at reference positions r (P, 3), given in
    time order, with velocities v (P, 3); runs of consecutive points inside the sphere get the
    detour of the module docstring."""
    dist = np.linalg.norm(r, axis=1)
    lifted = r.copy()
    inside = dist < d_min
    i = 0
    while i < len(r):
        if not inside[i]:
            i += 1
            continue
        j = i
        while j + 1 < len(r) and inside[j + 1]:
            j += 1
        run = slice(i, j + 1)
        m = i + int(np.argmin(dist[run]))
        chord = r[j] - r[i]
        c = v[m] if np.linalg.norm(v[m]) > 0.0 else chord
        if np.linalg.norm(c) == 0.0:
            c = r[m] if dist[m] > 0.0 else np.array([0.0, 1.0, 0.0])
        c = c / np.linalg.norm(c)
        miss = r[m] - (r[m] @ c) * c
        p = miss / np.linalg.norm(miss) if np.linalg.norm(miss) > _DEGENERATE_REL * d_min \
            else _orthogonal_unit(c)
        s = r[run] @ c
        q = r[run] @ p
        w = r[run] - np.outer(s, c) - np.outer(q, p)
        need = np.sqrt(np.maximum(d_min**2 - s**2 - np.sum(w**2, axis=1), 0.0))
        lifted[run] = np.outer(s, c) + np.outer(np.maximum(q, need), p) + w
        i = j + 1
    norms = np.linalg.norm(lifted, axis=1)
    return lifted / norms[:, None]


def _margins(t: FloatArray, v: FloatArray, d_min: float, pb: _Problem,
             base_m: float) -> FloatArray:
    """Extra radius (m) for the half-space at each keep-out point (times t, s, and reference
    velocities v, m/s).

    A straight segment of length l between two points at radius R dips to
    ``sqrt(R^2 - l^2/4) ~ R - l^2 / (8 R)`` midway (the sagitta), so a plan hugging the sphere
    at the constraint points would cut inside it between them.  Each point gets twice the
    sagitta of the longer of its two neighbouring gaps, ``l = |v_ref| gap``, plus ``base_m``
    for the solver residual; what remains (segments curved away from the target by thrust) is
    caught by the dense check.  Within one interval of either end the margin is scaled by
    ``(time to the end / h)^2``: the endpoints are fixed and may lie on the sphere itself, and a
    full margin right next to them could not be met (a tangential departure from the sphere
    gains radius only quadratically in time).
    """
    duration = pb.n_int * pb.h
    order = np.argsort(t, kind="stable")
    ts = np.concatenate([[0.0], t[order], [duration]])
    gaps = np.diff(ts)
    gap = np.empty_like(t)
    gap[order] = np.maximum(gaps[:-1], gaps[1:])
    chord = np.linalg.norm(v, axis=1) * gap
    ramp = np.minimum(1.0, (np.minimum(t, duration - t) / pb.h) ** 2)
    return (chord**2 / (4.0 * d_min) + base_m) * ramp


# --------------------------------------------------------------------------------------------
# the convex subproblem


_LpData = tuple[sp.csc_matrix, FloatArray, sp.csc_matrix, FloatArray, FloatArray]


def _scaled(pb: _Problem, x: FloatArray, u: FloatArray) -> FloatArray:
    """The OSQP variable vector z = [X/D, U/u_max, |U|/u_max] of a trajectory."""
    return np.concatenate([(x / pb.dscale).ravel(), (u / pb.u_max).ravel(),
                           np.abs(u / pb.u_max).ravel()])


def _build_lp(pb: _Problem, pts_k: npt.NDArray[np.int_], pts_tau: FloatArray,
              normals: FloatArray, margin: FloatArray,
              prox: tuple[FloatArray, float, float] | None = None,
              w_eq: float = 1.0, w_ko: float = 1.0) -> _LpData:
    """OSQP data (P, q, A, l, u) in the scaled variables z = [X/D, U/u_max, S/u_max].

    Cost: ``sum S`` (the L1 fuel divided by ``u_max h``) plus, when ``prox = (z_ref, w_x,
    w_u)``, ``w_x/2 |X/D - X_ref/D|^2 + w_u/2 |U/u_max - U_ref/u_max|^2``.
    Rows: dynamics (6N), x_0 and x_N (12), s - u >= 0 and s + u >= 0 (6N), |u| <= 1 (3N),
    keep-out half-spaces (one per point, divided by the length scale).  Dynamics and boundary
    rows are multiplied by ``w_eq`` and keep-out rows by ``w_ko`` (row weights, see
    :class:`ScpSettings`; they do not change the solution set).  The matrix is assembled
    directly in COO form (scipy's block helpers cost more than the solve at this size).
    """
    n_int, nx, nu = pb.n_int, pb.n_x, pb.n_u
    dsc = pb.dscale
    a_t = pb.ad * dsc[None, :] / dsc[:, None]
    b_t = pb.bd * pb.u_max / dsc[:, None]
    iu, is_ = nx, nx + nu
    k = np.arange(n_int)
    i6 = np.arange(6)
    # dynamics row 6k+i: X_{k+1,i} - A~[i,:] X_k - B~[i,:] U_k = 0
    dyn_row = (6 * k[:, None] + i6[None, :])  # (N, 6)
    r_list = [np.repeat(dyn_row.ravel(), 1), np.repeat(dyn_row.ravel(), 6),
              np.repeat(dyn_row.ravel(), 3)]
    c_list = [(6 * (k[:, None] + 1) + i6[None, :]).ravel(),
              np.broadcast_to((6 * k)[:, None, None] + i6[None, None, :], (n_int, 6, 6)).ravel(),
              np.broadcast_to(iu + (3 * k)[:, None, None] + np.arange(3)[None, None, :],
                              (n_int, 6, 3)).ravel()]
    v_list = [np.full(6 * n_int, w_eq), np.tile(-w_eq * a_t.ravel(), n_int),
              np.tile(-w_eq * b_t.ravel(), n_int)]
    # boundary rows: X_0 and X_N
    row0 = 6 * n_int
    r_list.append(row0 + np.arange(12))
    c_list.append(np.concatenate([i6, nx - 6 + i6]))
    v_list.append(np.full(12, w_eq))
    # slack rows (s - u >= 0, s + u >= 0) and the thrust box (|u| <= 1)
    row1 = row0 + 12
    j = np.arange(nu)
    r_list += [row1 + j, row1 + j, row1 + nu + j, row1 + nu + j, row1 + 2 * nu + j]
    c_list += [iu + j, is_ + j, iu + j, is_ + j, iu + j]
    v_list += [-np.ones(nu), np.ones(nu), np.ones(nu), np.ones(nu), np.ones(nu)]
    row2 = row1 + 3 * nu
    n_pts = len(pts_k)
    if n_pts:
        phi, gam = zoh_matrices(pb.n, pts_tau)
        scale = w_ko / pb.length
        cx = np.einsum("pi,pij->pj", normals, phi[:, :3, :]) * dsc[None, :] * scale
        cu = np.einsum("pi,pij->pj", normals, gam[:, :3, :]) * pb.u_max * scale
        r_list.append(row2 + np.repeat(np.arange(n_pts), 9))
        c_list.append(np.concatenate([6 * pts_k[:, None] + i6[None, :],
                                      iu + 3 * pts_k[:, None] + np.arange(3)[None, :]],
                                     axis=1).ravel())
        v_list.append(np.concatenate([cx, cu], axis=1).ravel())
    a_mat = sp.csc_matrix(
        (np.concatenate(v_list), (np.concatenate(r_list), np.concatenate(c_list))),
        shape=(row2 + n_pts, nx + 2 * nu))
    inf = np.inf
    x0_t, xf_t = w_eq * pb.x0 / dsc, w_eq * pb.xf / dsc
    lower = np.concatenate([
        np.zeros(6 * n_int), x0_t, xf_t, np.zeros(2 * nu), -np.ones(nu),
        ((pb.d_min or 0.0) + margin) * (w_ko / pb.length)])
    upper = np.concatenate([
        np.zeros(6 * n_int), x0_t, xf_t, np.full(2 * nu, inf), np.ones(nu),
        np.full(n_pts, inf)])
    q = np.zeros(nx + 2 * nu)
    q[is_:] = 1.0
    weights = np.zeros(nx + 2 * nu)
    if prox is not None:
        z_ref, w_x, w_u = prox
        weights[:nx] = w_x
        weights[iu:is_] = w_u
        q -= weights * z_ref
    p_mat = sp.diags(weights, format="csc")
    return p_mat, q, a_mat, lower, upper


_POLISH_OK = 1
"""OSQP ``info.status_polish`` of a successful polish."""
_APPROXIMATE = ("solved inaccurate", "maximum iterations reached", "run time limit reached")
"""OSQP statuses whose iterate is kept as an approximate answer."""


@dataclass
class _Solution:
    """One subproblem's outcome: scaled primal/dual (for warm starts), OSQP's status and the
    ADMM iterations spent."""

    status: str
    z: FloatArray | None
    y: FloatArray | None
    admm_iterations: int


def _solve_lp(data: _LpData, settings: ScpSettings, warm: _Solution | None,
              ladder: tuple[float, ...]) -> _Solution:
    """Set up and solve one subproblem, warm-started from the previous one (its primal, and
    its duals for the rows kept: rows are only ever appended).

    ADMM on an LP converges slowly at tight tolerances (it can stall at 1e-5 on a problem it
    solves at 1e-4), while polishing recovers the exact vertex once the active set is right.  So
    the tolerance is tightened along ``ladder``, continuing from the last iterate,
    until a polish succeeds; otherwise the last solved ADMM answer is used.
    """
    p_mat, q, a_mat, lower, upper = data
    solver = osqp.OSQP()
    opts: dict[str, Any] = {
        "verbose": False, "eps_abs": ladder[0], "eps_rel": ladder[0],
        "max_iter": settings.max_osqp_iter, "polishing": settings.polish,
        "warm_starting": True, "polish_refine_iter": 5,
    }
    if settings.time_limit_s > 0.0:
        opts["time_limit"] = settings.time_limit_s
    solver.setup(p_mat, q, a_mat, lower, upper, **opts)
    if warm is not None and warm.z is not None and warm.y is not None:
        y0 = np.zeros(a_mat.shape[0])
        m = min(len(y0), len(warm.y))
        y0[:m] = warm.y[:m]
        solver.warm_start(x=warm.z, y=y0)
    best = _Solution("unsolved", None, None, 0)
    iterations = 0
    for eps in ladder:
        solver.update_settings(eps_abs=eps, eps_rel=eps)
        res = solver.solve(raise_error=False)
        iterations += int(res.info.iter)
        status = str(res.info.status)
        if "infeasible" in status:
            if best.z is None:
                return _Solution(status, None, None, iterations)
            break
        approximate = status in _APPROXIMATE and np.all(np.isfinite(res.x))
        if status == "solved" or (approximate and best.z is None):
            # an iterate stopped by the iteration/time cap is still a usable approximation:
            # the caller re-propagates, cleans up and re-checks every constraint
            best = _Solution(status, np.array(res.x), np.array(res.y), iterations)
        if status != "solved" or res.info.status_polish == _POLISH_OK:
            break
    best.admm_iterations = iterations
    return best


def _terminal_cleanup(pb: _Problem, u: FloatArray, passes: int = 4) -> FloatArray:
    """Remove the solver's residual terminal error (ADMM tolerance sized, mm at most).

    Each pass takes the minimum-norm change of the inputs that are not at their bounds that
    zeroes the terminal error of the exact propagation (a 6 x m least-squares problem on the
    reachability matrix ``[Ad^(N-1-k) Bd]_k``, in scaled units), then clips to the bounds; a
    few passes settle the clipped components.  The change is small next to the margins, so the
    L1 cost and the keep-out are essentially unaffected (the keep-out is re-checked anyway).
    """
    blocks = np.empty((pb.n_int, 6, 3))
    m = pb.bd.copy()
    for k in range(pb.n_int - 1, -1, -1):
        blocks[k] = m
        m = pb.ad @ m
    reach = np.concatenate(list(blocks), axis=1) / pb.dscale[:, None]
    out = u.ravel().copy()
    for _ in range(passes):
        err = (_propagate_nodes(pb, out.reshape(u.shape))[-1] - pb.xf) / pb.dscale
        free = np.abs(out) < pb.u_max * (1.0 - 1e-9)
        if not np.any(err) or not np.any(free):
            break
        du, *_ = np.linalg.lstsq(reach[:, free], -err, rcond=None)
        out[free] = np.clip(out[free] + du, -pb.u_max, pb.u_max)
    return out.reshape(u.shape)


# --------------------------------------------------------------------------------------------
# SCP driver


@dataclass
class _Stats:
    """Solver effort of one planning call (reported in the plan)."""

    admm_iterations: int = 0
    lp_size: tuple[int, int, int] = (0, 0, 0)


def _plan(pb: _Problem, x: FloatArray, u: FloatArray, iterations: int, status: str,
          min_range: float, t_start: float, stats: _Stats) -> TransferPlan:
    def frozen(a: FloatArray) -> FloatArray:
        a = np.array(a, dtype=float)
        a.flags.writeable = False
        return a

    return TransferPlan(
        t_s=frozen(np.arange(pb.n_int + 1) * pb.h), x=frozen(x), u=frozen(u),
        dv_mps=float(np.sum(np.abs(u)) * pb.h), iterations=iterations,
        converged=status == STATUS_SOLVED, status=status, min_range_m=float(min_range),
        solve_time_s=time.perf_counter() - t_start, n_rad_s=pb.n,
        admm_iterations=stats.admm_iterations, lp_size=stats.lp_size)


def _keep_out_points(pb: _Problem, sub_points: int) -> tuple[npt.NDArray[np.int_], FloatArray]:
    """The first keep-out points, as (interval k, time tau into it, s): nodes 1..N-1 and
    ``sub_points`` inside every interval, in time order (x_0 is fixed: no point at 0)."""
    k_list = [k for k in range(pb.n_int) for _ in range(sub_points + 1)]
    tau_list = [j * pb.h / (sub_points + 1) for _ in range(pb.n_int) for j in range(sub_points + 1)]
    return np.array(k_list[1:], dtype=int), np.array(tau_list[1:])


def _subproblem(pb: _Problem, pts_k: npt.NDArray[np.int_], pts_tau: FloatArray,
                ref: tuple[FloatArray, FloatArray] | None, settings: ScpSettings) -> _LpData:
    """The convex subproblem about the reference plan ``ref`` = (node states, inputs): the
    keep-out linearised into half-spaces at the points (``pts_k``, ``pts_tau``), with the
    proximal term about ``ref``; without a reference (or a keep-out) the plan without it."""
    if ref is None or pb.d_min is None:
        return _build_lp(pb, pts_k[:0], pts_tau[:0], np.zeros((0, 3)), np.zeros(0), None,
                         settings.equality_row_weight)
    x_ref, u_ref = ref
    states = _states_in_intervals(pb, x_ref, u_ref, pts_k, pts_tau)
    order = np.argsort(pts_k * pb.h + pts_tau, kind="stable")
    normals = np.empty((len(pts_k), 3))
    normals[order] = _keep_out_normals(states[order, :3], states[order, 3:], pb.d_min)
    margin = _margins(pts_k * pb.h + pts_tau, states[:, 3:], pb.d_min, pb,
                      settings.keep_out_margin_m)
    prox = (_scaled(pb, x_ref, u_ref), settings.prox_state_weight, settings.prox_input_weight)
    return _build_lp(pb, pts_k, pts_tau, normals, margin, prox, settings.equality_row_weight,
                     settings.keep_out_row_weight)


def _unsolved_status(osqp_status: str, with_keep_out: bool) -> str:
    """The plan's status when a subproblem gave no usable iterate (OSQP's ``osqp_status``)."""
    if "primal infeasible" in osqp_status:
        return STATUS_INFEASIBLE_KEEP_OUT if with_keep_out else STATUS_INFEASIBLE_THRUST
    return f"{STATUS_SOLVER_FAILED}: {osqp_status}"


def _exact_answer(pb: _Problem, z: FloatArray, settings: ScpSettings
                  ) -> tuple[FloatArray, FloatArray, str | None]:
    """A subproblem's answer ``z`` made an exactly feasible plan: the inputs clipped to
    ``u_max``, the terminal residual removed (:func:`_terminal_cleanup`), the nodes propagated
    exactly.  Returns (node states, inputs, None), or a ``solver_failed`` status as the third
    item when the terminal error is still above ``settings.terminal_tol_m``."""
    u = z[pb.n_x:pb.n_x + pb.n_u].reshape(pb.n_int, 3) * pb.u_max
    u = _terminal_cleanup(pb, np.clip(u, -pb.u_max, pb.u_max))
    x = _propagate_nodes(pb, u)
    term = np.abs(x[-1] - pb.xf) / pb.dscale
    if np.max(term) > settings.terminal_tol_m / pb.length:
        return x, u, f"{STATUS_SOLVER_FAILED}: terminal error {np.max(term) * pb.length:.3g}"
    return x, u, None


def plan_transfer(
    n: float,
    x0: npt.ArrayLike,
    xf: npt.ArrayLike,
    duration_s: float,
    n_intervals: int,
    u_max_mps2: float,
    d_min_m: float | None = None,
    *,
    max_iters: int = 20,
    tol_m: float = 5e-2,
    settings: ScpSettings = ScpSettings(),  # noqa: B008 -- frozen, hence safe as a default
) -> TransferPlan:
    """Plan a fuel-optimal (L1) transfer from ``x0`` to ``xf`` with an optional keep-out sphere.

    Args:
        n: chief mean motion, rad/s.
        x0: initial HCW state at departure, m and m/s.
        xf: required state at arrival (``duration_s`` after departure), m and m/s.
        duration_s: transfer time T, s.
        n_intervals: number N of ZOH intervals (h = T/N).
        u_max_mps2: per-axis acceleration limit, m/s^2.
        d_min_m: keep-out radius about the target (LVLH origin), m; None for no keep-out.
        max_iters: cap on the convex subproblems solved.
        tol_m: SCP stops when no node moves more than this between iterates (and the cost has
            settled, see :class:`ScpSettings`), m.  The default (5 cm) sits above the iterate
            noise left by ADMM on the keep-out subproblems (1-2 cm measured on 50 m transfers);
            a smaller value mostly buys iterations that end in ``max_iterations``.
        settings: solver tuning.

    Returns:
        A :class:`TransferPlan`; check ``converged`` (status ``"solved"``) before flying it.
        Infeasibility (thrust too small for the duration, endpoints inside the sphere, no way
        around the sphere) and solver trouble are reported in ``status``, not raised.

    Raises:
        ValueError: malformed input (shapes, NaN, non-positive duration, limit or radius).
    """
    t_start = time.perf_counter()
    a0, af = _validate(n, x0, xf, duration_s, n_intervals, u_max_mps2, d_min_m, max_iters)
    pb = _make_problem(n, a0, af, float(duration_s), int(n_intervals), float(u_max_mps2),
                       d_min_m)
    coast_u = np.zeros((pb.n_int, 3))
    coast_x = _propagate_nodes(pb, coast_u)

    stats = _Stats()

    def failed(status: str, iterations: int) -> TransferPlan:
        rng, _ = _dense_check(pb, coast_x, coast_u, settings.check_points, None)
        return _plan(pb, coast_x, coast_u, iterations, status, rng, t_start, stats)

    if d_min_m is not None and min(np.linalg.norm(a0[:3]), np.linalg.norm(af[:3])) < d_min_m:
        return failed(STATUS_INFEASIBLE_ENDPOINT, 0)

    pts_k, pts_tau = _keep_out_points(pb, settings.sub_points)

    u_ref: FloatArray | None = None
    x_ref: FloatArray | None = None
    warm: _Solution | None = None
    cost_prev = math.inf
    min_range = math.inf
    best: tuple[float, FloatArray, FloatArray, float] | None = None  # cheapest safe iterate
    for it in range(1, max_iters + 1):
        with_keep_out = d_min_m is not None and x_ref is not None
        ref = (x_ref, u_ref) if x_ref is not None and u_ref is not None else None
        data = _subproblem(pb, pts_k, pts_tau, ref, settings)
        sol = _solve_lp(data, settings, warm, settings.eps_ladder_keep_out if with_keep_out
                        else settings.eps_ladder)
        stats.admm_iterations += sol.admm_iterations
        stats.lp_size = (data[2].shape[1], data[2].shape[0], data[2].nnz)
        if sol.z is None:
            status = _unsolved_status(sol.status, with_keep_out)
            if x_ref is not None and u_ref is not None and with_keep_out:
                # keep the last plan for information, but it is not a solution
                return _plan(pb, x_ref, u_ref, it, status, min_range, t_start, stats)
            return failed(status, it)
        warm = sol
        x_new, u_new, failure = _exact_answer(pb, sol.z, settings)
        if failure is not None:
            return failed(failure, it)
        min_range, viol = _dense_check(pb, x_new, u_new, settings.check_points, d_min_m)
        cost = float(np.sum(np.abs(u_new)) * pb.h)
        moved = math.inf if x_ref is None else float(np.max(np.abs(x_new[:, :3] - x_ref[:, :3])))
        settled = moved <= tol_m and abs(cost - cost_prev) <= max(
            settings.tol_cost_rel * cost, settings.tol_cost_abs_mps)
        if d_min_m is None or (not viol and (settled or x_ref is None)):
            # no keep-out, or safe and settled (an unconstrained plan that is already safe is
            # optimal for the keep-out problem too)
            return _plan(pb, x_new, u_new, it, STATUS_SOLVED, min_range, t_start, stats)
        if viol:
            pts_k = np.append(pts_k, [k for k, _ in viol])
            pts_tau = np.append(pts_tau, [tau for _, tau in viol])  # appended: rows keep order
        elif best is None or cost < best[0]:
            best = (cost, x_new, u_new, min_range)
        x_ref, u_ref, cost_prev = x_new, u_new, cost
    if best is not None:  # safe but not settled: the cheapest safe iterate
        _, x_best, u_best, range_best = best
        return _plan(pb, x_best, u_best, max_iters, STATUS_MAX_ITERATIONS, range_best, t_start,
                     stats)
    assert x_ref is not None and u_ref is not None
    return _plan(pb, x_ref, u_ref, max_iters, STATUS_KEEP_OUT_VIOLATED, min_range, t_start,
                 stats)
