"""Model predictive control (MPC) for HCW trajectory tracking, solved with OSQP.

The guidance app runs :class:`MpcTracker` at the low rate to track a planned
trajectory (a fuel-optimal transfer or a passive relative orbit) and applies the
first input as an acceleration held constant (zero-order hold) over the next
step.  This is the "model predictive control formulation of the convexified
problem" with an L1 fuel cost of the paper (Sec. II.B).

Problem solved at every step (horizon ``H``, step ``dt``; ``e_k = x_k - r_k`` is
the tracking error against the reference states ``r_k``, ``u_k`` the
acceleration and ``w_k`` the planned feed-forward acceleration)::

    minimise   sum_{k=1}^{H-1} e_k' Q e_k  +  s_f e_H' Q e_H
             + r_l1   * dt   * sum_{k=0}^{H-1} ||u_k - w_k||_1
             + r_quad * dt^2 * sum_{k=0}^{H-1} ||u_k - w_k||_2^2
    subject to x_0 = measured state,
               x_{k+1} = Ad x_k + Bd u_k          (exact ZOH HCW, hcw.discretize)
               |u_k,i| <= u_max                  (per axis)

with ``Q = diag(q_pos I3, q_vel I3)`` and ``s_f = q_terminal_scale``.  The fuel
terms are written on the velocity increment ``Δv_k = u_k dt`` so that ``r_l1`` is
a price per m/s of Δv, independent of the step.  The 1-norm is expressed with
slack variables ``t_k >= |u_k - w_k|`` (the standard LP epigraph form, Boyd &
Vandenberghe, *Convex Optimization*, Sec. 4.3 / 6.1); the problem is then the
QP ``min 1/2 z'Pz + q'z  s.t.  l <= Az <= u`` that OSQP solves (Stellato et al.,
"OSQP: an operator splitting solver for quadratic programs", Math. Prog. Comp.
12, 2020).

Scaling.  OSQP's termination tests are absolute/relative tolerances on the
variables, so all variables are made O(1) in physically meaningful units:
inputs are divided by ``u_max`` (unscaled, the solver stalls at the iteration
cap, see REFERENCE.md), velocity errors by ``u_max dt`` (the Δv of one
full-thrust step) and position errors by ``u_max dt^2``.  In these units the
discrete double integrator inside the HCW model reads ``[[1, 1], [0, 1]]`` with
input column ``[1/2, 1]``, so every matrix entry is O(1).  The error
formulation puts the reference only into the equality right-hand side
(``e_{k+1} = Ad e_k + Bd u_k + (Ad r_k - r_{k+1})``): each step updates the
vectors ``l``, ``u`` (and ``q`` when a feed-forward is given), never the matrices,
so OSQP is set up (and its KKT matrix factorised) once.

Warm start.  The previous primal and dual solutions are shifted by one step,
the last step repeated (the usual receding-horizon initial guess; Rawlings,
Mayne & Diehl, *Model Predictive Control: Theory, Computation, and Design*,
2nd ed., 2017), and passed to OSQP.  A failed solve drops the warm start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import osqp
import scipy.sparse as sp

from gnc.checks import finite_array
from gnc.hcw import discretize

__all__ = ["MpcConfig", "MpcResult", "MpcTracker"]

FloatArray = npt.NDArray[np.float64]

_NX = 6
_NU = 3


@dataclass(frozen=True)
class MpcConfig:
    """Tuning of the tracking MPC.

    Defaults are chosen for observers on 20-100 m passive relative orbits at
    about 500 km (n ≈ 1.1e-3 rad/s, so one 10 s step is 0.6° of orbit and the
    default 20-step horizon, 200 s, about 1/28 of an orbit) with cold-gas-class
    thrust (u_max ≈ 1e-3 m/s²: one step of full thrust is 1 cm/s of Δv).

    Reasoning behind the weights (the cost is dimensionless; with
    ``r_l1 = 10 s/m`` one mm/s of Δv is priced at 0.01):

    * ``q_pos = 0.03 /m²``: a position error held over the horizon counts in 19
      running steps plus the terminal step (x100), i.e. 119 weighted steps.  A
      0.1 m error then costs 0.03 * 0.01 * 119 ≈ 0.036, the price of 3.6 mm/s of
      Δv, so the MPC will spend a few mm/s on it.  A 1 cm error costs the price
      of ≈ 36 µm/s, less than the two-burn correction of it inside the
      horizon (≈ 2 * 0.01 m / 200 s = 0.1 mm/s), so it is left alone: the L1
      term gives a dead band (measured 5-9 mm in position, ≈ 10 µm/s in
      velocity) in which the optimal thrust is zero: no chattering around a
      natural orbit.
    * ``q_vel = 3e3 /(m/s)²``: q_vel / q_pos = 1e5 s², so a velocity error δv
      weighs as much as the position error δv * 316 s.  This sets the time
      scale of corrections: a 2 m, 5 mm/s offset is removed in ≈ 850 s (0.15
      orbit) for 1.1-2.4 cm/s of Δv, 1.7-2.7x the fuel-optimal open-loop
      correction of the same duration (linear program; the 200 s horizon
      cannot plan the slower, cheaper drift-assisted corrections).  A larger
      q_pos / q_vel makes corrections faster and dearer (q_pos = 1,
      q_vel = 1e3: ≈ 100 s but ≈ 8 cm/s for the same offset).
    * ``q_terminal_scale = 100``: the terminal error stands for all the error
      after the horizon; weighting it strongly keeps the MPC from starting a
      correction whose braking burn falls beyond the horizon and tightens the
      steady state (≈ 2 cm with 1e-6 m/s² of unmodelled along-track
      acceleration).
    * ``r_quad = 1 /(m/s)²``: only there for strict convexity in the inputs; at
      Δv of a few cm/s per step it is ≈ 1e-3 of the L1 term (it would matter
      only for Δv ≈ r_l1 / r_quad = 10 m/s per step).

    OSQP settings: ``eps_abs = eps_rel = 1e-4`` act on the scaled variables
    (position 1e-4 * 0.1 m = 10 µm, velocity 1e-4 * 1 cm/s = 1 µm/s, input
    1e-4 * u_max).  ``polish`` (on by default) re-solves on the identified
    active set, so inputs inside the dead band come out exactly zero instead
    of zero to the tolerance.  Without it, tolerance-level thrusts (≈ 1e-7
    m/s²) are commanded at every step and, being below the dead band, are never
    corrected: on an exact natural orbit with ``q_terminal_scale = 1`` they
    summed to 2.7 mm/s and a 9 cm wander over 10 orbits (zero with polishing).
    Polishing costs one more factorisation, ≈ 0.3 ms per solve; when it fails
    (wrong active-set guess) OSQP keeps the ADMM solution.  ``max_iter`` bounds
    the solve time; a solve that reaches it is reported, not raised.

    Attributes:
        dt_s: MPC step and ZOH hold time, s.
        horizon: number of steps H in the prediction horizon.
        u_max_mps2: per-axis acceleration limit, m/s².
        q_pos: weight on squared position error, 1/m².
        q_vel: weight on squared velocity error, 1/(m/s)².
        q_terminal_scale: factor on Q for the terminal error (dimensionless).
        r_l1: weight per m/s of L1 Δv, Σ_k ||u_k - w_k||_1 dt, s/m.
        r_quad: weight on Σ_k ||(u_k - w_k) dt||², 1/(m/s)².
        eps_abs: OSQP absolute tolerance (on scaled variables).
        eps_rel: OSQP relative tolerance.
        max_iter: OSQP iteration cap (a solve that reaches it is reported, ok=False).
        polish: run OSQP's solution polishing.
    """

    dt_s: float = 10.0
    horizon: int = 20
    u_max_mps2: float = 1e-3
    q_pos: float = 0.03
    q_vel: float = 3e3
    q_terminal_scale: float = 100.0
    r_l1: float = 10.0
    r_quad: float = 1.0
    eps_abs: float = 1e-4
    eps_rel: float = 1e-4
    max_iter: int = 4000
    polish: bool = True

    def __post_init__(self) -> None:
        def positive(name: str) -> None:
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0.0):
                raise ValueError(f"MpcConfig.{name} must be positive and finite, got {v!r}")

        def non_negative(name: str) -> None:
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0.0):
                raise ValueError(f"MpcConfig.{name} must be non-negative and finite, got {v!r}")

        for name in ("dt_s", "u_max_mps2", "eps_abs", "eps_rel"):
            positive(name)
        for name in ("q_pos", "q_vel", "q_terminal_scale", "r_l1", "r_quad"):
            non_negative(name)
        for name in ("horizon", "max_iter"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"MpcConfig.{name} must be an integer >= 1, got {v!r}")


@dataclass(frozen=True)
class MpcResult:
    """Outcome of one MPC solve.

    Attributes:
        u0: acceleration to apply now (held over dt), m/s², shape (3,); zeros
            when ``ok`` is False.
        u: planned accelerations over the horizon, m/s², shape (H, 3); zeros
            when ``ok`` is False.
        x_pred: predicted states ``[x, y, z, vx, vy, vz]`` (m, m/s) at
            t, t+dt, ..., t+H dt under ``u``, shape (H+1, 6).
        status: OSQP status string (e.g. "solved", "maximum iterations reached").
        ok: True only when OSQP reports "solved".
        iterations: ADMM iterations used.
        solve_time_s: OSQP's own run time for this call (update + solve + polish), s.
    """

    u0: FloatArray
    u: FloatArray
    x_pred: FloatArray
    status: str
    ok: bool
    iterations: int
    solve_time_s: float


class MpcTracker:
    """Receding-horizon tracker of an HCW reference trajectory (OSQP, set up once).

    Decision vector (all scaled, see the module docstring)::

        z = [ξ_0 .. ξ_H | v_0 .. v_{H-1} | t_0 .. t_{H-1}]

    with ``ξ_k = S⁻¹ e_k`` (6 each), ``v_k = u_k / u_max`` and slacks ``t_k``
    (3 each).  Constraint rows, in order: initial condition (6), dynamics
    (6H), input box ``-1 <= v_k <= 1`` (3H), ``v_k - t_k <= v_ref,k`` (3H),
    ``v_k + t_k >= v_ref,k`` (3H).
    """

    def __init__(self, n: float, config: MpcConfig | None = None) -> None:
        """Build the QP and call OSQP setup once.

        Args:
            n: chief mean motion, rad/s.
            config: tuning; defaults to ``MpcConfig()``.
        """
        cfg = MpcConfig() if config is None else config
        self.config = cfg
        self.n = float(n)
        h = int(cfg.horizon)
        self._h = h
        ad, bd = discretize(self.n, cfg.dt_s)
        self._ad = ad
        self._bd = bd

        # Variable scaling: e = S ξ, u = u_max v.
        pos_scale = cfg.u_max_mps2 * cfg.dt_s**2
        vel_scale = cfg.u_max_mps2 * cfg.dt_s
        self._s = np.array([pos_scale] * 3 + [vel_scale] * 3)
        self._s_inv = 1.0 / self._s
        ad_s = self._s_inv[:, None] * ad * self._s[None, :]
        bd_s = self._s_inv[:, None] * bd * cfg.u_max_mps2

        nx_tot = _NX * (h + 1)
        nu_tot = _NU * h
        self._ix_v = nx_tot
        self._ix_t = nx_tot + nu_tot
        self._nz = nx_tot + 2 * nu_tot

        # Cost.  OSQP minimises 1/2 z'Pz + q'z, hence the factors of 2 on P.
        q_diag = np.array([cfg.q_pos] * 3 + [cfg.q_vel] * 3) * self._s**2
        stage = np.concatenate([np.zeros(_NX)] + [q_diag] * (h - 1)
                               + [cfg.q_terminal_scale * q_diag])
        self._p_v = 2.0 * cfg.r_quad * (cfg.u_max_mps2 * cfg.dt_s) ** 2
        p_diag = np.concatenate([2.0 * stage, np.full(nu_tot, self._p_v), np.zeros(nu_tot)])
        p_mat = sp.diags(p_diag, format="csc")
        self._q_base = np.zeros(self._nz)
        self._q_base[self._ix_t:] = cfg.r_l1 * cfg.u_max_mps2 * cfg.dt_s

        # Constraints.
        # rows 0..5: ξ_0; rows 6(k+1)..: ξ_{k+1} - Ãd ξ_k - B̃ v_k
        a_dyn = sp.hstack(
            [
                sp.eye(nx_tot) - sp.kron(sp.eye(h + 1, k=-1), ad_s),
                -sp.kron(sp.eye(h + 1, h, k=-1), bd_s),
                sp.csc_matrix((nx_tot, nu_tot)),
            ]
        )
        eye_u = sp.eye(nu_tot)
        zero_x = sp.csc_matrix((nu_tot, nx_tot))
        zero_u = sp.csc_matrix((nu_tot, nu_tot))
        a_box = sp.hstack([zero_x, eye_u, zero_u])
        a_lo = sp.hstack([zero_x, eye_u, -eye_u])
        a_hi = sp.hstack([zero_x, eye_u, eye_u])
        a_mat = sp.vstack([a_dyn, a_box, a_lo, a_hi], format="csc")
        self._m = a_mat.shape[0]
        self._row_box = nx_tot
        self._row_lo = nx_tot + nu_tot
        self._row_hi = nx_tot + 2 * nu_tot

        self._l = np.zeros(self._m)
        self._u = np.zeros(self._m)
        self._l[self._row_box:self._row_lo] = -1.0
        self._u[self._row_box:self._row_lo] = 1.0
        self._l[self._row_lo:self._row_hi] = -np.inf
        self._u[self._row_hi:] = np.inf

        self._solver = osqp.OSQP()
        self._solver.setup(
            p_mat, self._q_base.copy(), a_mat, self._l.copy(), self._u.copy(),
            verbose=False, eps_abs=cfg.eps_abs, eps_rel=cfg.eps_rel, max_iter=int(cfg.max_iter),
            polishing=bool(cfg.polish), warm_starting=True,
            # rho adapted every 25 iterations (a fixed count; 0 would tie it to the measured
            # set-up time), so the same inputs give the same iterates on every machine;
            # termination checked every 5 iterations since warm starts converge in tens
            adaptive_rho_interval=25, check_termination=5,
        )
        self._warm: tuple[FloatArray, FloatArray] | None = None
        self._rho0 = float(self._solver.settings.rho)
        # Whether the last solve adapted ρ.  OSQP keeps an adapted ρ for the next solve, a
        # state no warm start carries: it is set back first, so that a solve depends on its
        # inputs and warm start alone (a restarted process, its warm start restored, solves
        # as the one that stopped would have).
        self._rho_moved = False
        self._shift_x = self._shift_index(
            [(0, h + 1, _NX), (self._ix_v, h, _NU), (self._ix_t, h, _NU)], self._nz)
        self._shift_y = self._shift_index(
            [(0, h + 1, _NX), (self._row_box, h, _NU), (self._row_lo, h, _NU),
             (self._row_hi, h, _NU)], self._m)

    @property
    def horizon(self) -> int:
        """Number of steps H in the horizon."""
        return self._h

    def reset(self) -> None:
        """Drop the warm start (e.g. after a new plan); the next solve starts cold."""
        self._warm = None

    @property
    def warm(self) -> tuple[FloatArray, FloatArray] | None:
        """The warm start of the next solve (primal, dual), None for a cold one: with it, a
        rebuilt tracker solves as this one would (a restart's critical data)."""
        return self._warm

    @warm.setter
    def warm(self, value: tuple[FloatArray, FloatArray] | None) -> None:
        self._warm = value

    @staticmethod
    def _shift_index(blocks: list[tuple[int, int, int]], size: int) -> npt.NDArray[np.intp]:
        """Gather index that shifts each block of ``count`` steps of width ``width`` (starting at
        ``start``) forward by one step, repeating the last step; other entries are kept."""
        idx = np.arange(size)
        for start, count, width in blocks:
            steps = np.minimum(np.arange(count) + 1, count - 1)
            idx[start:start + count * width] = (start + steps[:, None] * width
                                                + np.arange(width)[None, :]).ravel()
        return idx

    def _shifted_warm_start(self, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Shift a previous primal/dual solution by one step (last step repeated).

        Primal: states ξ_0..ξ_H, inputs and slacks.  Dual: the initial-condition and dynamics
        rows carry the costates λ_0..λ_H; box and slack rows one block per input step.
        """
        return x[self._shift_x], y[self._shift_y]

    def _free_prediction(self, x0: FloatArray) -> FloatArray:
        """States over the horizon with zero input, m and m/s, shape (H+1, 6)."""
        out = np.empty((self._h + 1, _NX))
        out[0] = x0
        for k in range(self._h):
            out[k + 1] = self._ad @ out[k]
        return out

    def solve(
        self,
        x0: npt.ArrayLike,
        x_ref: npt.ArrayLike,
        u_ref: npt.ArrayLike | None = None,
    ) -> MpcResult:
        """Solve one MPC step.

        Args:
            x0: current state ``[x, y, z, vx, vy, vz]``, m and m/s, shape (6,).
            x_ref: reference states at t, t+dt, ..., t+H dt, shape (H+1, 6).
            u_ref: optional feed-forward accelerations of the plan over the
                horizon, m/s², shape (H, 3); fuel is charged on ``u - u_ref``.

        Returns:
            An :class:`MpcResult`.  A solver failure is reported through
            ``ok``/``status`` (with zero inputs), never raised.

        Raises:
            ValueError: on wrong shapes or non-finite inputs.
        """
        h = self._h
        cfg = self.config
        x0a = finite_array("x0", x0, (_NX,))
        ref = finite_array("x_ref", x_ref, (h + 1, _NX))
        v_ref = np.zeros((h, _NU))
        if u_ref is not None:
            v_ref = finite_array("u_ref", u_ref, (h, _NU)) / cfg.u_max_mps2

        # equality rows: ξ_0 = S⁻¹(x0 - r_0);  ξ_{k+1} - Ãd ξ_k - B̃ v_k = S⁻¹(Ad r_k - r_{k+1})
        rhs = np.empty((h + 1, _NX))
        rhs[0] = x0a - ref[0]
        rhs[1:] = ref[:-1] @ self._ad.T - ref[1:]
        rhs *= self._s_inv
        nx_tot = self._row_box
        self._l[:nx_tot] = rhs.ravel()
        self._u[:nx_tot] = self._l[:nx_tot]
        vr = v_ref.ravel()
        self._u[self._row_lo:self._row_hi] = vr
        self._l[self._row_hi:] = vr
        q = self._q_base.copy()
        q[self._ix_v:self._ix_t] = -self._p_v * vr
        self._solver.update(q=q, l=self._l, u=self._u)

        if self._warm is None:
            self._solver.warm_start(x=np.zeros(self._nz), y=np.zeros(self._m))
        else:
            self._solver.warm_start(x=self._warm[0], y=self._warm[1])

        if self._rho_moved:  # each solve starts from the same ρ: see __init__
            self._solver.update_settings(rho=self._rho0)
        res = self._solver.solve(raise_error=False)
        self._rho_moved = int(res.info.rho_updates) > 0
        status = str(res.info.status)
        iters = int(res.info.iter)
        run_time = float(res.info.run_time)
        z = np.array(res.x, dtype=float, copy=True)
        ok = status == "solved" and z.shape == (self._nz,) and bool(np.all(np.isfinite(z)))
        if not ok:
            self._warm = None
            return MpcResult(
                u0=np.zeros(_NU), u=np.zeros((h, _NU)), x_pred=self._free_prediction(x0a),
                status=status, ok=False, iterations=iters, solve_time_s=run_time,
            )
        y = np.array(res.y, dtype=float, copy=True)
        self._warm = self._shifted_warm_start(z, y)
        # never command beyond the limit (OSQP meets the box only to its tolerance)
        v = np.clip(z[self._ix_v:self._ix_t].reshape(h, _NU), -1.0, 1.0)
        u = v * cfg.u_max_mps2
        x_pred = ref + z[: self._ix_v].reshape(h + 1, _NX) * self._s
        return MpcResult(
            u0=u[0].copy(), u=u, x_pred=x_pred, status=status, ok=True,
            iterations=iters, solve_time_s=run_time,
        )
