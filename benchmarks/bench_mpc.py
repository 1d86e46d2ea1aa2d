"""Speed of the OSQP tracking MPC (fsw/lib/mpc.py): set-up time and warm-started solve time per
step.

    python benchmarks/bench_mpc.py [--steps N] [--horizon H] [--dt S] [--seed N]

Closed loop at 500 km: an observer starts 2 m / 5 mm/s off a 50 m PRO and tracks it for N steps
under an unmodelled constant acceleration (1e-6 m/s² class) and white velocity noise standing in
for navigation error (seeded).  The plant is the exact ZOH HCW model.  For each variant (default
settings, polishing off, cold start at every step) it prints OSQP's own run time per solve
(median, p90, max), the wall time of the whole `solve` call, iteration counts, solver statuses and
the Δv spent.  Set-up time is the time to build an MpcTracker (QP assembly + OSQP setup).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from fsw.lib.mpc import MpcConfig, MpcTracker  # noqa: E402
from gnc import hcw  # noqa: E402


def closed_loop(n: float, cfg: MpcConfig, steps: int, rng: np.random.Generator,
                cold: bool) -> dict[str, object]:
    """Run one closed loop and collect per-step timings and iteration counts."""
    h = cfg.horizon
    ref = np.array([hcw.pro_state(n, 50.0, 0.3, 5.0, 60.0, 1.0, t=k * cfg.dt_s)
                    for k in range(steps + h + 1)])
    ad, bd = hcw.discretize(n, cfg.dt_s)
    disturbance = np.array([3e-7, 1e-6, -5e-7])
    noise = rng.normal(0.0, 1e-5, (steps, 3))
    mpc = MpcTracker(n, cfg)
    x = ref[0] + np.array([2.0, 0.0, 0.0, 0.005, 0.0, 0.0])
    osqp_t, wall_t, iters, statuses = [], [], [], []
    dv = 0.0
    for k in range(steps):
        if cold:
            mpc.reset()
        w0 = time.perf_counter()
        r = mpc.solve(x, ref[k:k + h + 1])
        wall_t.append(time.perf_counter() - w0)
        osqp_t.append(r.solve_time_s)
        iters.append(r.iterations)
        statuses.append(r.status)
        dv += float(np.abs(r.u0).sum() * cfg.dt_s)
        x = ad @ x + bd @ (r.u0 + disturbance)
        x[3:] += noise[k]
    err = float(np.linalg.norm(x[:3] - ref[steps, :3]))
    return {"osqp": np.array(osqp_t), "wall": np.array(wall_t), "iters": np.array(iters),
            "statuses": statuses, "dv": dv, "final_err": err}


def setup_time(n: float, cfg: MpcConfig, repeats: int = 20) -> tuple[float, float]:
    """Median and max wall time to construct an MpcTracker, s."""
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        MpcTracker(n, cfg)
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), float(np.max(ts))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--steps", type=int, default=400, help="closed-loop steps per variant")
    p.add_argument("--horizon", type=int, default=20)
    p.add_argument("--dt", type=float, default=10.0, help="MPC step, s")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()

    n = hcw.mean_motion(500e3)
    base = MpcConfig(dt_s=args.dt, horizon=args.horizon)
    s_med, s_max = setup_time(n, base)
    print(f"MPC: horizon {base.horizon}, dt {base.dt_s:g} s, n = {n:.5e} rad/s, "
          f"{args.steps} closed-loop steps per variant")
    print(f"set-up (QP build + OSQP setup): median {s_med * 1e3:.2f} ms, max {s_max * 1e3:.2f} ms")
    variants = [
        ("warm, polish (default)", base, False),
        ("warm, no polish", replace(base, polish=False), False),
        ("cold every step, polish", base, True),
    ]
    head = (f"{'variant':<26} {'osqp med ms':>11} {'p90':>7} {'max':>7} {'wall med':>9} "
            f"{'iter med':>8} {'p90':>5} {'max':>5} {'not ok':>6} {'dv m/s':>8} {'err m':>7}")
    print(head)
    for name, cfg, cold in variants:
        r = closed_loop(n, cfg, args.steps, np.random.default_rng(args.seed), cold)
        o, w, it = r["osqp"], r["wall"], r["iters"]
        assert (isinstance(o, np.ndarray) and isinstance(w, np.ndarray)
                and isinstance(it, np.ndarray))
        statuses = r["statuses"]
        assert isinstance(statuses, list)
        bad = sum(s != "solved" for s in statuses)
        print(f"{name:<26} {np.median(o) * 1e3:>11.3f} {np.percentile(o, 90) * 1e3:>7.3f} "
              f"{o.max() * 1e3:>7.3f} {np.median(w) * 1e3:>9.3f} {np.median(it):>8.0f} "
              f"{np.percentile(it, 90):>5.0f} {it.max():>5d} {bad:>6d} {r['dv']:>8.4f} "
              f"{r['final_err']:>7.4f}")


if __name__ == "__main__":
    main()
