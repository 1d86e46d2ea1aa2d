"""Speed of the SCP transfer planner (fsw/lib/scp.py): wall time per transfer, SCP iterations,
OSQP iterations and LP size, with and without the keep-out sphere.

    python benchmarks/bench_scp.py [--count N] [--seed S] [--intervals N] [--d-min M]

Random transfers at 500 km (seeded): the observer starts 20-50 m from the target in a random
direction with a 1 cm/s-class velocity and must arrive 20-50 m on the opposite side (so many
straight paths cross the keep-out sphere) in 600-1500 s, with u_max = 1e-3 m/s^2 per axis.  Each
transfer is planned without keep-out and with it; the table gives medians (and p90/max) of the
wall time of the whole ``plan_transfer`` call.  "crossing" rows are the keep-out plans whose
unconstrained plan entered the sphere (those that need SCP iterations).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from fsw.lib.scp import TransferPlan, plan_transfer  # noqa: E402
from gnc import hcw  # noqa: E402

U_MAX = 1e-3


def random_transfer(rng: np.random.Generator, n_int: int | None) -> tuple[np.ndarray, np.ndarray,
                                                                          float, int]:
    """One random opposite-side transfer: (x0, xf, duration_s, intervals)."""
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    r0 = d * rng.uniform(20.0, 50.0)
    rf = -d * rng.uniform(20.0, 50.0) + rng.normal(0.0, 3.0, 3)
    x0 = np.concatenate([r0, rng.normal(0.0, 0.01, 3)])
    xf = np.concatenate([rf, rng.normal(0.0, 0.01, 3)])
    duration = float(rng.uniform(600.0, 1500.0))
    return x0, xf, duration, n_int if n_int is not None else int(rng.integers(30, 80))


def row(label: str, plans: list[TransferPlan]) -> str:
    if not plans:
        return f"{label:<22} {'(none)':>6}"
    t = 1e3 * np.array([p.solve_time_s for p in plans])
    its = np.array([p.iterations for p in plans])
    admm = np.array([p.admm_iterations for p in plans])
    size = np.array([p.lp_size for p in plans])
    solved = sum(p.converged for p in plans)
    return (f"{label:<22} {len(plans):>6} {solved:>7} {np.median(t):>9.1f} "
            f"{np.percentile(t, 90):>8.1f} {t.max():>8.1f} {np.median(its):>6.0f} {its.max():>5d} "
            f"{np.median(admm):>8.0f} {np.median(size[:, 0]):>6.0f} {np.median(size[:, 1]):>6.0f} "
            f"{np.median(size[:, 2]):>7.0f}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--count", type=int, default=30, help="random transfers")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--intervals", type=int, default=None,
                   help="ZOH intervals per transfer (default: random 30-79)")
    p.add_argument("--d-min", type=float, default=10.0, help="keep-out radius, m")
    args = p.parse_args()
    n = hcw.mean_motion(500e3)
    rng = np.random.default_rng(args.seed)
    free, keep_out, crossing = [], [], []
    fuel_ratio = []
    for _ in range(args.count):
        x0, xf, duration, n_int = random_transfer(rng, args.intervals)
        pf = plan_transfer(n, x0, xf, duration, n_int, U_MAX)
        pk = plan_transfer(n, x0, xf, duration, n_int, U_MAX, args.d_min)
        free.append(pf)
        keep_out.append(pk)
        if pf.min_range_m < args.d_min:
            crossing.append(pk)
            if pk.converged and pf.converged:
                fuel_ratio.append(pk.dv_mps / pf.dv_mps)
    print(f"SCP transfers at 500 km, u_max {U_MAX} m/s^2, keep-out {args.d_min} m, "
          f"{args.count} random transfers (seed {args.seed})")
    print(f"{'':<22} {'plans':>6} {'solved':>7} {'med ms':>9} {'p90 ms':>8} {'max ms':>8} "
          f"{'SCP it':>6} {'max':>5} {'ADMM it':>8} {'vars':>6} {'rows':>6} {'nnz':>7}")
    print(row("no keep-out", free))
    print(row("keep-out (all)", keep_out))
    print(row("keep-out (crossing)", crossing))
    statuses: dict[str, int] = {}
    for plan in keep_out:
        statuses[plan.status] = statuses.get(plan.status, 0) + 1
    print("keep-out statuses:", statuses)
    if fuel_ratio:
        print(f"crossing transfers: keep-out / unconstrained fuel median "
              f"{np.median(fuel_ratio):.3f} (max {max(fuel_ratio):.3f}); "
              f"min range of keep-out plans {min(p.min_range_m for p in crossing):.4f} m")


if __name__ == "__main__":
    main()
