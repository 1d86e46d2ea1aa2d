"""Attitude library speed: the 10 Hz attitude-cycle functions before/after gnc.quat, and
scp_slew per 90° slew.

    python benchmarks/bench_attitude.py [--calls N] [--slews N] [--no-slew]

Cycle table: for mekf_propagate, mekf_update, tracking_torque, SlerpPlan.at, SlewPlan.at,
repoint and lvlh_to_eci_quat, the median (and p90) wall time of one call ("after"), and of the scipy
``Rotation``/``Slerp`` operations the function used to do ("scipy core") against the
:mod:`gnc.quat` code that replaced them ("quat core").  The former implementation is gone,
so "before" is estimated as ``after − quat core + scipy core`` (the rest of each function,
input checks and linear algebra, is unchanged).  For mekf_propagate the cores include
``mekf_transition``, whose one-filter path now uses floats: the old path is timed by calling it
with a batch of one, which runs the former array code.

Slew table: one ``scp_slew`` for a 90° rest-to-rest slew in 60 s at several node counts and
rate limits, with the SCP iteration count and the exact-kinematics landing error.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from fsw.lib.attitude import SlewPlan, repoint, scp_slew, slerp_plan  # noqa: E402
from fsw.lib.attitude_control import AttitudeGains, tracking_torque  # noqa: E402
from fsw.lib.mekf import mekf_propagate, mekf_transition, mekf_update  # noqa: E402
from gnc import quat  # noqa: E402
from gnc.frames import lvlh_to_eci_quat  # noqa: E402

J = np.array([[0.10, 0.006, -0.004], [0.006, 0.12, 0.003], [-0.004, 0.003, 0.08]])
DT = 0.1  # s, attitude cycle
SIGMA_V, SIGMA_U = 4.4e-5, 2.4e-7  # gyro noise, rad/√s and rad/s^1.5


def _times(fn: Callable[[], object], repeats: int) -> list[float]:
    fn()  # warm-up (imports, caches)
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return out


def _p90(xs: list[float]) -> float:
    return float(np.percentile(xs, 90))


def _median_us(fn: Callable[[], object], calls: int) -> tuple[float, float]:
    """Median and p90 of one call, µs."""
    ts = _times(fn, calls)
    return statistics.median(ts) * 1e6, _p90(ts) * 1e6


# One case: (name, the library call, the scipy operations it used to do, the quat code now).
Case = tuple[str, Callable[[], object], Callable[[], object], Callable[[], object]]


def _cycle_cases(rng: np.random.Generator) -> list[Case]:
    """The attitude-cycle calls with representative inputs, and their old/new rotation cores."""
    q = Rotation.random(random_state=rng).as_quat()
    q_meas = (Rotation.from_quat(q) * Rotation.from_rotvec([1e-4, -2e-4, 5e-5])).as_quat()
    b = np.array([1e-5, -2e-5, 3e-6])
    P = np.diag([1e-6] * 3 + [1e-10] * 3)
    w_meas = np.array([0.01, -0.02, 0.015])
    w_hat = w_meas - b
    R = np.diag([1e-9, 1e-9, 1e-8])
    dx = np.array([1e-5, 2e-5, -1e-5])

    r_est, r_des = Rotation.random(random_state=rng), Rotation.random(random_state=rng)
    w_est, w_des, wdot_des, h = rng.normal(size=(4, 3)) * 0.01
    gains = AttitudeGains.gains_for(10.0, 0.9, w_max_radps=0.05)

    def torque_scipy() -> object:
        d_rot = r_des.inv() * r_est
        return d_rot.as_quat(), d_rot.as_matrix()

    def torque_quat() -> object:
        dq = quat.canonical(quat.mul(quat.conj(r_des.as_quat()), r_est.as_quat()))
        return quat.rotate_inv(dq, w_des), quat.rotate_inv(dq, wdot_des)

    slerp_p = slerp_plan(r_est, r_des, 0.0, 60.0)
    slerp_ref = Slerp([0.0, 60.0], Rotation.concatenate([r_est, r_des]))
    r1 = r_est * Rotation.from_rotvec(math.radians(90.0) * np.array([1.0, 2.0, -1.0]) / 6**0.5)
    slew = scp_slew(r_est, r1, 60.0, 31, 0.05, w0=np.zeros(3), w1=np.zeros(3))
    slew_ref = Slerp(slew.t_s, Rotation.from_quat(slew.q))
    t_at = 33.3

    los, bore = np.array([1.0, 2.0, 3.0]) / 14**0.5, np.array([0.0, 0.0, 1.0])

    def repoint_scipy() -> object:
        a = r_est.apply(bore)
        axis = np.cross(a, los)
        s = float(np.linalg.norm(axis))
        return Rotation.from_rotvec(axis / s * math.atan2(s, float(a @ los))) * r_est

    def repoint_quat() -> object:
        q_prev = r_est.as_quat()
        a = quat.rotate(q_prev, bore)
        axis = quat.cross(a, los)
        s = math.hypot(*axis.tolist())
        turn = axis * (math.atan2(s, float(a @ los)) / s)
        return Rotation.from_quat(quat.mul(quat.exp(turn), q_prev))

    orbit = (1234.5, 1.1e-3, math.radians(51.6), 0.3, 0.2)
    lvlh_matrix = quat.to_matrix(lvlh_to_eci_quat(*orbit))

    return [
        ("mekf_propagate", lambda: mekf_propagate(q, b, P, w_meas, DT, SIGMA_V, SIGMA_U),
         lambda: (mekf_transition(w_hat[None], DT, SIGMA_V, SIGMA_U),
                  (Rotation.from_quat(q) * Rotation.from_rotvec(w_hat * DT)).as_quat()),
         lambda: (mekf_transition(w_hat, DT, SIGMA_V, SIGMA_U),
                  quat.mul(q, quat.exp(w_hat * DT)))),
        ("mekf_update", lambda: mekf_update(q, b, P, q_meas, R),
         lambda: ((Rotation.from_quat(q).inv() * Rotation.from_quat(q_meas)).as_rotvec(),
                  (Rotation.from_quat(q) * Rotation.from_rotvec(dx)).as_quat()),
         lambda: (quat.log(quat.mul(quat.conj(q), q_meas)), quat.mul(q, quat.exp(dx)))),
        ("tracking_torque",
         lambda: tracking_torque(r_est, w_est, r_des, w_des, wdot_des, J, h, gains, 2e-3),
         torque_scipy, torque_quat),
        ("SlerpPlan.at", lambda: slerp_p.at(t_at), lambda: slerp_ref(t_at),
         lambda: Rotation.from_quat(slerp_p.at_quat(t_at)[0])),
        ("SlewPlan.at", lambda: slew.at(t_at), lambda: slew_ref(t_at),
         lambda: Rotation.from_quat(slew.at_quat(t_at)[0])),
        ("repoint", lambda: repoint(r_est, los, bore), repoint_scipy, repoint_quat),
        ("lvlh_to_eci_quat", lambda: lvlh_to_eci_quat(*orbit),
         lambda: Rotation.from_matrix(lvlh_matrix),
         lambda: Rotation.from_quat(lvlh_to_eci_quat(*orbit))),
    ]


def bench_cycle(calls: int) -> None:
    """Print the before/after table of the attitude-cycle functions."""
    print(f"attitude-cycle calls, median (p90) µs over {calls} calls:")
    print(f"{'function':>16} {'before (est.)':>14} {'after':>16} {'speed-up':>9} "
          f"{'scipy core':>11} {'quat core':>10}")
    total_before = total_after = 0.0
    for name, call, scipy_core, quat_core in _cycle_cases(np.random.default_rng(0)):
        after, after_p90 = _median_us(call, calls)
        old_core, _ = _median_us(scipy_core, calls)
        new_core, _ = _median_us(quat_core, calls)
        before = after - new_core + old_core
        total_before += before
        total_after += after
        print(f"{name:>16} {before:>14.1f} {after:>7.1f} ({after_p90:>6.1f}) "
              f"{before / after:>8.1f}x {old_core:>11.1f} {new_core:>10.1f}")
    print(f"{'sum':>16} {total_before:>14.1f} {total_after:>7.1f}")


def bench_slew(slews: int) -> None:
    r0 = Rotation.from_euler("xyz", [10.0, 20.0, 30.0], degrees=True)
    r1 = r0 * Rotation.from_rotvec(math.radians(90.0) * np.array([1.0, 2.0, -1.0]) / math.sqrt(6.0))
    zero = np.zeros(3)
    print("scp_slew, 90° rest-to-rest in 60 s:")
    print(f"{'nodes':>6} {'w_max rad/s':>12} {'status':>10} {'iters':>6} {'median ms':>10} "
          f"{'p90 ms':>8} {'landing rad':>12} {'max|w|/w_max':>13}")
    for n_nodes, w_max in ((31, 0.05), (31, 0.03), (61, 0.03), (121, 0.03), (31, 0.014)):
        plans: list[SlewPlan] = []

        def call(n_nodes: int = n_nodes, w_max: float = w_max,
                 plans: list[SlewPlan] = plans) -> object:
            plans.append(scp_slew(r0, r1, 60.0, n_nodes, w_max, w0=zero, w1=zero))
            return plans[-1]

        ts = _times(call, slews)
        p = plans[-1]
        print(f"{n_nodes:>6} {w_max:>12.3f} {p.status:>10} {p.iterations:>6} "
              f"{statistics.median(ts) * 1e3:>10.2f} {_p90(ts) * 1e3:>8.2f} "
              f"{p.terminal_error_rad:>12.1e} {np.max(np.abs(p.w)) / w_max:>13.4f}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--calls", type=int, default=2000, help="calls per attitude-cycle function")
    p.add_argument("--slews", type=int, default=20, help="scp_slew runs per configuration")
    p.add_argument("--no-slew", action="store_true", help="skip the scp_slew table")
    args = p.parse_args()
    bench_cycle(args.calls)
    if not args.no_slew:
        bench_slew(args.slews)


if __name__ == "__main__":
    main()
