"""Navigation filter consistency in real (in-process) runs against the nonlinear truth (NEES /
NIS chi-square tests over Monte Carlo seeds)."""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

from deploy.inproc import run_inproc
from ground.archive.recorder import McapRecorder
from harness.archive.reader import load_run
from harness.summary.nav import nav_errors
from tests.conftest import small_scenario


def test_nees_and_nis_consistent_over_monte_carlo_runs(tmp_path) -> None:  # noqa: ANN001
    """Monte Carlo over independent seeds (Bar-Shalom, Ch. 5.4): the average NEES at each time
    over M runs x N observers is chi-square with 6MN dof divided by MN; the NIS is white, so its
    mean over all updates is tightly bounded."""
    runs, settle_s = 8, 20.0
    nees_by_t: dict[float, list[float]] = {}
    nis_all: list[float] = []
    for seed in range(runs):
        sc = small_scenario(seed=seed, duration_s=150.0,
                            rates={"high_hz": 1.0, "mid_hz": 1.0, "low_hz": 0.1})
        path = tmp_path / f"nav{seed}.mcap"
        with McapRecorder(path) as rec:
            run_inproc(sc, tap=rec.record, ground=False)
        for e in nav_errors(load_run(path), sc.name).values():
            for t, q, nis in zip(e.t_s, e.nees, e.nis, strict=True):
                if t >= settle_s:
                    nees_by_t.setdefault(round(t, 3), []).append(q)
                    if np.isfinite(nis):
                        nis_all.append(nis)
    n = len(next(iter(nees_by_t.values())))
    assert n == runs * 3
    anees = np.array([np.mean(v) for v in nees_by_t.values()])
    lo, hi = chi2.ppf([0.025, 0.975], 6 * n) / n
    inside = np.mean((anees >= lo) & (anees <= hi))
    assert inside > 0.85, f"ANEES inside 95% bounds {inside:.2f}"
    assert lo < anees.mean() < hi
    k = len(nis_all)
    lo, hi = chi2.ppf([0.0005, 0.9995], 6 * k) / k
    assert lo < np.mean(nis_all) < hi
