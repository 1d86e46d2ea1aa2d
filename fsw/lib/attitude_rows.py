"""The attitude apps' 10 Hz cycle over the spacecraft of one fleet, as rows of arrays: the
hot state of every attitude app in one block (``interfaces.runtime.rows``), stepped by one
compiled call (:func:`step_rows`) that loops over the rows with the same per-row kernels the
app calls alone (``fsw.lib.attitude_kernels``), so every row's bits equal its app's own step.

A row's cycle (``fsw.apps.attitude.AttitudeApp.step``, paper Sec. II.B): the MEKF propagated
with the gyro and updated with the star tracker, then the torque that follows the slew plan
in force, or the tracking cycle onto the pointing target.  A row whose cycle would leave the
compiled path (a slew to plan, no line of sight, a torque not finite) is left untouched and
reported, for its app to step alone: its error, if any, is its own.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from fsw.lib import attitude_kernels as kern
from gnc import quat
from interfaces.contracts.timing import TIME_TOL_S
from interfaces.runtime.rows import Field, Rows

MAX_NODES = 16
"""The slew nodes a new block holds room for (grown when a plan has more)."""

CONSTANTS = ("kp", "kd", "w_limit", "tau_max", "slew_threshold_rad", "sigma_v", "sigma_u",
             "n", "inclination_rad", "raan_rad", "arg_lat0_rad")
"""The columns of a row's ``const``: gains (``fsw.lib.attitude_control.gains_for``; rate
limit < 0: none), torque limit N·m, slew threshold rad, gyro noise (ARW rad/√s, bias walk
rad/s^1.5), and the target's orbit as the LVLH model flies it (rad/s, rad)."""

STATE: dict[str, Field] = {
    "q": Field((4,), optional=True), "b": Field((3,)), "P": Field((6, 6)),
    "nis": Field(optional=True), "t_att": Field(optional=True), "t_star": Field(optional=True),
    "h_wheels": Field((3,)), "tau": Field((3,)), "w_est": Field((3,)),
    "x_est": Field((6,)), "target": Field((3,)), "target_rate": Field((3,)),
    "target_accel": Field((3,)), "target_t": Field(), "q_point": Field((4,), optional=True),
    "slew_t0": Field(), "slew_end": Field(),
}
"""The MEKF and the loop: what the app learns while running, each field one of its
``CRITICAL`` attributes (a ``Row``), checkpointed and restored through it."""

NODES: dict[str, Field] = {
    "slew_t": Field((MAX_NODES,)), "slew_q": Field((MAX_NODES, 4)),
    "slew_phi": Field((MAX_NODES, 3)), "slew_w": Field((MAX_NODES, 3)),
    "slew_count": Field((2,), dtype=np.int64),
}
"""The slew plan in force as its nodes (times s, unit quaternions, rotation vectors, body
rates; their counts): written from the plan whenever it is set (:func:`set_slew`), restored
with it."""

INPUTS: dict[str, Field] = {
    "t_meas": Field(), "gyro": Field((3,)), "star": Field((4,)), "star_on": Field(dtype=bool),
    "r_diag": Field((3,)), "t_est": Field(), "slewing": Field(dtype=bool),
}
"""This cycle's inputs, staged by each app before the compiled call: the measurement, the
nav estimate's time, whether the slew plan is followed."""

CONSTANT: dict[str, Field] = {
    "J": Field((3, 3)), "boresight": Field((3,)), "const": Field((len(CONSTANTS),)),
}
"""What the scenario sets, written when the app is built."""

SPEC: dict[str, Field] = STATE | NODES | INPUTS | CONSTANT
"""The fields of the attitude apps' block: only :data:`STATE` is learnt while running."""

TRACKED, SLEW, NO_LINE_OF_SIGHT = kern.TRACKED, kern.SLEW, kern.NO_LINE_OF_SIGHT
FOLLOWED = 3
"""A row's status: the slew plan in force followed (the torque computed)."""
NOT_FINITE = 4
"""A row's status: the torque is not finite (its app steps alone: safe mode)."""
DONE = (TRACKED, FOLLOWED)
"""The statuses of a row whose cycle is done (its state advanced)."""


def new_rows(n: int = 1) -> Rows:
    """A block of ``n`` attitude rows."""
    return Rows(SPEC, n)


def set_slew(rows: Rows, i: int, nodes: tuple[np.ndarray, ...] | None) -> None:
    """Row ``i``'s slew plan: its nodes (times s (M,), unit quaternions (M, 4), rotation
    vectors (M − 1, 3), body rates (K, 3)), or None."""
    counts = rows.data["slew_count"]
    if nodes is None:
        counts[i] = 0
        return
    t_s, q, phi, w = nodes
    m = max(len(t_s), len(w))
    for name in ("slew_t", "slew_q", "slew_phi", "slew_w"):
        rows.fit(name, (m, *rows.spec[name].shape[1:]))
    d = rows.data
    for name, value in (("slew_t", t_s), ("slew_q", q), ("slew_phi", phi), ("slew_w", w)):
        d[name][i, :len(value)] = value
    counts[i] = (len(t_s), len(w))


def step_rows(rows: Rows, which: np.ndarray, t: float, dt: float, h: float, report: bool
              ) -> np.ndarray:
    """One cycle at ``t`` (s) of rows ``which`` (int, in the block ``rows``, their inputs set):
    each row's status (:data:`DONE` or why it was left untouched), -1 for rows not stepped.
    ``dt``: the tick (s); ``h``: the step of the desired rate's central difference (s);
    ``report``: the cycle reports the estimate, which needs a line of sight (a row following
    its slew plan without one is left: its report's error is its own)."""
    d, s = rows.data, rows.is_set
    return _step_rows(
        which, t, dt, h, report, d["q"], d["b"], d["P"], d["nis"], s["nis"], d["t_att"],
        d["t_star"], s["t_star"], d["h_wheels"], d["tau"], d["w_est"], d["x_est"], d["target"],
        d["target_rate"], d["target_accel"], d["target_t"], d["q_point"], s["q_point"],
        d["slew_t0"], d["slew_t"], d["slew_q"], d["slew_phi"], d["slew_w"], d["slew_count"],
        d["t_meas"], d["gyro"], d["star"], d["star_on"], d["r_diag"], d["t_est"], d["slewing"],
        d["J"], d["boresight"], d["const"])


_hamilton = njit(cache=True)(quat.hamilton)


@njit(cache=True)
def slew_sample(t_nodes: np.ndarray, q_nodes: np.ndarray, phi: np.ndarray, rates: np.ndarray,
                m: int, k_rates: int, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The slew plan's attitude, body rate and acceleration at ``t`` (s from its start): the
    first ``m`` nodes and ``k_rates`` rates of the arrays.  As the plan's ``at_quat``
    (``fsw.lib.attitude``'s node path: constant-rate short-way rotations between nodes)."""
    zero = np.zeros(3)
    tc = min(max(t, t_nodes[0]), t_nodes[m - 1])
    k = max(int(np.searchsorted(t_nodes[:m], tc, side="left")) - 1, 0)
    frac = (tc - t_nodes[k]) / (t_nodes[k + 1] - t_nodes[k])
    qk, v = q_nodes[k], phi[k] * frac
    q_t = np.array(_hamilton((qk[0], qk[1], qk[2], qk[3]), kern._exp_xyz(v[0], v[1], v[2])))
    if t < t_nodes[0] or t > t_nodes[m - 1]:
        return q_t, zero, zero.copy()
    j = int(np.searchsorted(t_nodes[:m], t, side="right")) - 1
    j = min(max(j, 0), k_rates - 1)
    return q_t, rates[j].copy(), zero


@njit(cache=True)
def _step_rows(which, t, dt, h, report, q, b, P, nis, nis_set, t_att, t_star, t_star_set, h_wheels,
               tau, w_est, x_est, target, target_rate, target_accel, target_t, q_point,
               point_set, slew_t0, slew_t, slew_q, slew_phi, slew_w, slew_count, t_meas, gyro,
               star, star_on, r_diag, t_est, slewing, J, boresight, const):  # noqa: ANN001,ANN202
    status = np.full(len(q), -1, dtype=np.int64)
    for r in which:
        c = const[r]
        kp, kd, w_limit, tau_max, threshold, sigma_v, sigma_u = c[0], c[1], c[2], c[3], c[4], \
            c[5], c[6]
        qn, bn, Pn = q[r], b[r], P[r]
        dtm = t_meas[r] - t_att[r]
        if dtm > TIME_TOL_S:
            qn, bn, Pn = kern.mekf_propagate(qn, bn, Pn, gyro[r], dtm, sigma_v, sigma_u)
        nis_r = nis[r]
        if star_on[r]:
            qn, bn, Pn, nis_r = kern.mekf_update(qn, bn, Pn, star[r], np.diag(r_diag[r]))
        w_e = gyro[r] - bn
        q_des = qn
        if slewing[r]:
            qd, wd, wdd = slew_sample(slew_t[r], slew_q[r], slew_phi[r], slew_w[r],
                                      slew_count[r, 0], slew_count[r, 1], t - slew_t0[r])
            tau_r, _ = kern.tracking_torque(qn, w_e, qd, wd, wdd, J[r], h_wheels[r], kp, kd,
                                            w_limit, tau_max)
            done = FOLLOWED
            if report:
                los = kern.los_eci(t, c[7], c[8], c[9], c[10], x_est[r], t_est[r], target[r],
                                   target_rate[r], target_accel[r], target_t[r])
                n2 = los[0] * los[0] + los[1] * los[1] + los[2] * los[2]
                if not (n2 > 0.0 and np.isfinite(n2)):
                    done = NO_LINE_OF_SIGHT
        else:
            seed = q_point[r] if point_set[r] else qn
            done, _, q_des, _, tau_r = kern.track_cycle(
                t, h, c[7], c[8], c[9], c[10], x_est[r], t_est[r], target[r], target_rate[r],
                target_accel[r], target_t[r], seed, qn, w_e, boresight[r], J[r], h_wheels[r],
                kp, kd, w_limit, tau_max, threshold)
        if done != TRACKED and done != FOLLOWED:
            status[r] = done
            continue
        if not np.isfinite(tau_r).all():
            status[r] = NOT_FINITE
            continue
        q[r], b[r], P[r], t_att[r], w_est[r], tau[r] = qn, bn, Pn, t_meas[r], w_e, tau_r
        if star_on[r]:
            nis[r], nis_set[r], t_star[r], t_star_set[r] = nis_r, True, t_meas[r], True
        h_wheels[r] = h_wheels[r] - tau_r * dt
        if done == TRACKED:
            q_point[r], point_set[r] = q_des, True
        status[r] = done
    return status
