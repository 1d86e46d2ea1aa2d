"""Guidance app: PRO insertion, reconfiguration and station keeping (paper Sec. II.B, Fig. 7).

Rate group low (ω_low).  Inputs: the ground's PRO assignments, the nav state estimate and the
attitude estimate (to express thrust in body axes).  Outputs: the thrust command to the
thrusters, the transfer plan when one is made, and the guidance status.

A new assignment is kept pending (the current orbit is still held) until its departure time;
then the app plans a fuel-optimal transfer to
the assigned PRO's state at the arrival time — SCP with an L1 fuel cost, per-axis thrust limit and
a keep-out sphere (``fsw.lib.scp``), the terminal state energy matched (``gnc.pro``) — and
tracks the plan, then the PRO, with the MPC (``fsw.lib.mpc``) every cycle.  The first MPC input is
held for one cycle (ZOH), converted from LVLH to body axes with the attitude estimate.  With no
assignment the spacecraft drifts (no thrust); without an attitude estimate, or while the
attitude app is slewing, it does not fire (the MPC closes the gap on the next cycles).  The
status reports the acceleration actually commanded, which nav uses as its known input.

Thrust limits: body thrusters give |F_j| ≤ F_max per axis; any LVLH acceleration with
|u|∞ ≤ F_max / (m √3) maps into body axes within that limit whatever the attitude, so that is the
MPC's limit, and the plan uses ``guidance.plan_thrust_fraction`` of it to leave a margin.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from fsw.lib.mpc import MpcConfig, MpcTracker
from fsw.lib.scp import TransferPlan, plan_transfer
from gnc import hcw
from gnc.pro import Pro, energy_matched_state
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    AttitudeEstimate,
    GuidanceStatus,
    OnboardCommand,
    ProAssignment,
    ProAssignments,
    StateEstimate,
    ThrustCommand,
    TransferPlanMsg,
)
from interfaces.contracts.timing import TIME_TOL_S
from interfaces.runtime.app import App, AppContext, Input, Output

MIN_TRANSFER_S = 120.0
"""Shortest transfer planned when an assignment arrives late, s."""
KEEP_OUT_MARGIN_M = 0.5
"""Transfers are planned this far outside the keep-out sphere, m: the MPC tracks the plan to a
few centimetres, and a plan that grazes the sphere would otherwise be flown millimetres inside
it (measured: 7.9925 m against 8 m over two orbits)."""
MAX_INTERVALS = 200
"""Most SCP intervals per transfer; longer transfers get wider node spacing."""


class GuidanceApp(App):
    NAME = "guidance"
    RATE = "low"
    INPUTS = (
        Input(cat.ASSIGNMENTS, "on_assignments"),
        Input(cat.NAV_ESTIMATE, "on_estimate"),
        Input(cat.ATTITUDE_ESTIMATE, "on_attitude"),
        Input(cat.FDIR_COMMAND, "on_command"),
    )
    OUTPUTS = (
        Output("thrust", cat.THRUST),
        Output("plan", cat.TRANSFER_PLAN),
        Output("status", cat.GUIDANCE_STATUS),
    )
    CRITICAL = ("assignment", "pending", "previous", "refused_id", "pro", "plan", "plan_t0",
                "planned_id", "dv_commanded", "_est", "_att", "mpc.warm", "safe_from")

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.sc_id = ctx.spacecraft or 0
        self.n = ctx.constants.n_rad_s
        self.chief_radius_m = ctx.constants.chief_radius_m
        self.dt = 1.0 / sc.rates.low_hz
        self.mass = sc.observers.mass_kg
        self.u_max = sc.actuators.thruster_max_force_n / (self.mass * math.sqrt(3.0))
        self.min_impulse = sc.actuators.thruster_min_impulse_ns
        self.cfg = sc.guidance
        self.mpc = MpcTracker(self.n, MpcConfig(dt_s=self.dt, horizon=self.cfg.mpc_horizon,
                                                u_max_mps2=self.u_max))
        self.assignment: ProAssignment | None = None  # the one being flown
        self.pending: ProAssignment | None = None     # received, departure still ahead
        self.previous: tuple[ProAssignment | None, Pro | None] = (None, None)
        self.refused_id = 0
        self.pro: Pro | None = None
        self.plan: TransferPlan | None = None
        self.plan_t0 = 0.0
        self.planned_id = 0
        self.dv_commanded = 0.0
        self._est: StateEstimate | None = None
        self._att: AttitudeEstimate | None = None
        self.safe_from: int | None = None
        """in the onboard FDIR's safe hold since this assignment id was the newest (None: not)"""

    # --- inputs ------------------------------------------------------------------------------

    def on_assignments(self, msg: ProAssignments) -> None:
        """Keep the newest assignment as pending until its departure time."""
        mine = [a for a in msg.assignments if a.spacecraft == self.sc_id]
        newest = max([a.assignment_id for a in (self.assignment, self.pending) if a]
                     + [self.refused_id])
        if mine and mine[0].assignment_id > newest:
            self.pending = mine[0]
            self.log.info("assignment %d (%s) received: depart %.0f s, arrive %.0f s",
                          mine[0].assignment_id, mine[0].phase, mine[0].t_depart_s,
                          mine[0].t_arrive_s)

    def on_estimate(self, msg: StateEstimate) -> None:
        self._est = msg

    def on_attitude(self, msg: AttitudeEstimate) -> None:
        self._att = msg

    def on_command(self, msg: OnboardCommand) -> None:
        """The onboard FDIR's safe hold: no thrust and no transfer until an assignment newer
        than every one received so far (fsw/apps/fdir.py)."""
        if msg.command == "safe_hold" and self.safe_from is None:
            self.safe_from = max([a.assignment_id for a in (self.assignment, self.pending) if a]
                                 + [self.refused_id])
            self.log.warning("safe hold (onboard FDIR): thrust off until an assignment newer "
                             "than %d", self.safe_from)

    # --- cycle ---------------------------------------------------------------------------------

    def step(self, t: float) -> None:
        if self._in_safe_hold():
            self._status(t, "safe")
            return
        if self.pending is not None and t >= self.pending.t_depart_s - TIME_TOL_S:
            self._activate(self.pending)
            self.pending = None
        a = self.assignment
        if self._est is None or a is None or self.pro is None:
            self._status(t, "idle")
            return
        x = _propagate(self.n, np.array(self._est.x), t - self._est.t_sim)
        if a.assignment_id != self.planned_id:
            self._plan(t, x, a)
            if self.assignment is None or self.pro is None:  # refused, nothing to fall back on
                self._status(t, "idle")
                return
        refs, u_ref = self._reference(t)
        res = self.mpc.solve(x, refs, u_ref)
        u = res.u0 if res.ok else np.zeros(3)
        if not res.ok:
            self.log.warning("MPC %s at t=%.0f s: no thrust this cycle", res.status, t)
        u = self._command(t, u)
        mode = ("transfer" if self.plan is not None and t < self.plan_t0 + self.plan.t_s[-1]
                else "hold")
        err = x - refs[0]
        self._status(t, mode, err, u, res.status, 1e3 * res.solve_time_s)

    def _in_safe_hold(self) -> bool:
        """Whether safe hold goes on: it ends when a newer assignment has been received."""
        if self.safe_from is None:
            return False
        if self.pending is not None and self.pending.assignment_id > self.safe_from:
            self.log.warning("safe hold ended by assignment %d", self.pending.assignment_id)
            self.safe_from = None
            return False
        return True

    def _activate(self, a: ProAssignment) -> None:
        """Fly assignment ``a`` from now (its transfer is planned in this cycle)."""
        self.previous = (self.assignment, self.pro)
        self.assignment = a
        self.pro = Pro.of(a.pro)

    def _plan(self, t: float, x: np.ndarray, a: ProAssignment) -> None:
        """Plan the transfer to the assigned PRO.  If no safe plan exists, the assignment is
        refused and the previous orbit kept (the MPC alone has no keep-out constraint), and
        the refusal published (a plan not solved); an assignment already due with the
        spacecraft near its PRO is held directly.  One received more than a cycle after its
        departure (held for a pass) takes the transfer time it asked for from now."""
        self.planned_id = a.assignment_id
        self.plan = None
        self.mpc.reset()
        duration = a.t_arrive_s - t
        if duration <= 0.0 and a.t_depart_s >= a.t_arrive_s:
            return  # a hold from the start (no transfer in the command)
        if t - a.t_depart_s > self.dt and a.t_arrive_s > a.t_depart_s:
            duration = max(duration, a.t_arrive_s - a.t_depart_s)  # late: the time asked
        duration = max(duration, MIN_TRANSFER_S)
        d_min = min(self.cfg.keep_out_m + KEEP_OUT_MARGIN_M, 0.9 * float(np.linalg.norm(x[:3])))
        # Too short for the planning thrust: use the full limit, then take longer.
        attempts = [(duration, self.cfg.plan_thrust_fraction * self.u_max)] + [
            (duration * 1.5**k, self.u_max) for k in range(3)]
        for duration, u_max in attempts:
            try:
                plan = self._solve_transfer(t, x, duration, u_max, d_min)
            except ValueError as e:
                self.log.error("assignment %d refused: %s", a.assignment_id, e)
                self.publish("plan", TransferPlanMsg(
                    sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id,
                    assignment_id=a.assignment_id, t_s=[], x=[], u_mps2=[], dv_mps=0.0,
                    status="refused", iterations=0, min_range_m=0.0, solve_ms=0.0))
                self._revert()
                return
            if plan.status != "infeasible_thrust_limit":
                break
            self.log.warning("transfer %d infeasible in %.0f s at %.2g m/s²", a.assignment_id,
                             duration, u_max)
        self.log.info("transfer %d planned: %s, %.1f mm/s, %d iterations, %.0f ms",
                      a.assignment_id, plan.status, 1e3 * plan.dv_mps, plan.iterations,
                      1e3 * plan.solve_time_s)
        self.publish("plan", TransferPlanMsg(
            sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id, assignment_id=a.assignment_id,
            t_s=(t + plan.t_s).tolist(), x=plan.x.tolist(), u_mps2=plan.u.tolist(),
            dv_mps=plan.dv_mps, status=plan.status, iterations=plan.iterations,
            min_range_m=max(0.0, plan.min_range_m), solve_ms=1e3 * plan.solve_time_s))
        if plan.converged:
            self.plan, self.plan_t0 = plan, t
        else:
            self.log.error("transfer %d: SCP %s; assignment refused, keeping the previous orbit",
                           a.assignment_id, plan.status)
            self._revert()

    def _revert(self) -> None:
        """Refuse the current assignment for good and go back to the previous one (drift if
        there was none)."""
        assert self.assignment is not None
        self.refused_id = self.assignment.assignment_id
        self.assignment, self.pro = self.previous
        self.planned_id = self.assignment.assignment_id if self.assignment else 0
        self.plan = None

    def _solve_transfer(self, t: float, x: np.ndarray, duration: float, u_max: float,
                        d_min: float) -> TransferPlan:
        """SCP transfer from ``x`` now to the assigned PRO's energy-matched state ``duration``
        seconds later, with nodes every ``guidance.node_spacing_s``."""
        assert self.pro is not None
        intervals = min(MAX_INTERVALS, max(4, int(math.ceil(duration / self.cfg.node_spacing_s))))
        xf = energy_matched_state(self.pro.state(self.n, t + duration), self.chief_radius_m)
        return plan_transfer(self.n, x, xf, duration, intervals, u_max, d_min)

    def _reference(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Reference states at t + j·dt (j = 0..H) and feed-forward inputs (j = 0..H-1)."""
        assert self.pro is not None
        h = self.cfg.mpc_horizon
        times = t + self.dt * np.arange(h + 1)
        refs = self.pro.states(self.n, times)
        u_ref = np.zeros((h, 3))
        plan = self.plan
        if plan is not None:
            tau = times - self.plan_t0
            inside = np.flatnonzero(tau <= plan.t_s[-1])
            if inside.size:
                refs[inside] = plan.states_at(tau[inside])  # one vectorised propagation
                fed = inside[inside < h]
                step = np.minimum((tau[fed] // plan.t_s[1]).astype(int), len(plan.u) - 1)
                u_ref[fed] = plan.u[step]
        return refs, u_ref

    def _command(self, t: float, u_lvlh: np.ndarray) -> np.ndarray:
        """Send the thrust for acceleration ``u_lvlh``; return the acceleration commanded (zero
        when the thrusters cannot fire: no attitude estimate yet, or the spacecraft is slewing,
        which would turn the body-fixed thrust during the burn).  Body axes whose impulse over
        the cycle is below the minimum impulse bit are not commanded (the thrusters would not
        fire them), so nav and the Δv count see what is really flown."""
        if self._att is None or self._att.mode != "track" or not u_lvlh.any():
            return np.zeros(3)
        r_lvlh_body = Rotation.from_quat(self._att.q_lvlh_body)
        force_body = self.mass * r_lvlh_body.inv().apply(u_lvlh)
        force_body[np.abs(force_body) * self.dt < self.min_impulse] = 0.0
        if not force_body.any():
            return np.zeros(3)
        u_lvlh = r_lvlh_body.apply(force_body) / self.mass
        self.dv_commanded += float(np.abs(u_lvlh).sum()) * self.dt
        self.publish("thrust", ThrustCommand(
            sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id,
            force_body_n=force_body.tolist(), duration_s=self.dt))
        return u_lvlh

    def _status(self, t: float, mode: str, err: np.ndarray | None = None,
                u: np.ndarray | None = None, mpc_status: str = "", mpc_ms: float = 0.0) -> None:
        a = self.assignment
        self.publish("status", GuidanceStatus(
            sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id, mode=mode,  # type: ignore[arg-type]
            assignment_id=a.assignment_id if a else 0, phase=a.phase if a else "",
            pro=a.pro if a else None,
            pos_error_m=float(np.linalg.norm(err[:3])) if err is not None else 0.0,
            vel_error_mps=float(np.linalg.norm(err[3:])) if err is not None else 0.0,
            accel_lvlh_mps2=(u if u is not None else np.zeros(3)).tolist(),
            dv_commanded_mps=self.dv_commanded, mpc_status=mpc_status, mpc_ms=mpc_ms))


def _propagate(n: float, x: np.ndarray, dt: float) -> np.ndarray:
    """HCW propagation of an estimate to the cycle time (dt ≥ 0, usually 0)."""
    return x if abs(dt) < TIME_TOL_S else hcw.hcw_stm(n, dt) @ x
