"""The run report's FDIR plot (fdir.png): per observer shown, each of the ground's tests as
its statistic over its threshold, window by window (log10: a test fails above 0), and each
declaration where the statistic of the test that declared it stood, named by that test.

The tests plotted are those the windows carry (``FdirWindow``): the information test H_m,i
against τ_i (Eq. 9, 11-12), the window's NIS test (Σ NIS against its χ²(6N) quantile) and,
with the sequential test, the image scan's and the NIS scan's largest statistic in the window
against their thresholds.  A declaration by a test the windows do not carry (a link check,
the global check) is marked at its own statistic over its threshold, or on the threshold
line when it has none.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from harness.report_scale import figure_height_in  # noqa: E402
from harness.summary import Detection, RunSummary  # noqa: E402
from harness.summary.declaring import LABELS  # noqa: E402
from harness.summary.fdir import detection_test  # noqa: E402
from interfaces.contracts.messages import FdirWindow  # noqa: E402

SERIES: tuple[tuple[str, str, str], ...] = (
    ("information test: H_m,i / τ_i", "metric", "threshold"),
    ("window NIS test: Σ NIS / χ² quantile", "nis_sum", "nis_limit"),
    ("image scan: max |Z| / c", "scan_z_max", "scan_threshold"),
    ("NIS scan: max z / c_nis", "nis_scan_z_max", "nis_scan_threshold"))
"""Each test the windows carry: its label, its statistic's field and its threshold's."""

FLOOR = -3.0
"""log10 of a margin of zero (a statistic of zero), as drawn."""


def log_margin(statistic: float | None, threshold: float | None) -> float | None:
    """log10(statistic / threshold), at least ``FLOOR``; None without both or a threshold
    that is not positive."""
    if statistic is None or threshold is None or threshold <= 0.0:
        return None
    return max(math.log10(statistic / threshold), FLOOR) if statistic > 0.0 else FLOOR


def margins(windows: list[FdirWindow]) -> dict[str, tuple[list[float], list[float]]]:
    """Each test's (window ends, s; log10 margins) over ``windows`` (one observer's), for the
    tests with any."""
    out = {}
    for label, stat, thr in SERIES:
        points = [(w.t_end_s, log_margin(getattr(w, stat), getattr(w, thr))) for w in windows]
        kept = [(t, m) for t, m in points if m is not None]
        if kept:
            out[label] = ([t for t, _ in kept], [m for _, m in kept])
    return out


def plot_fdir(out: Path, windows: list[FdirWindow], shown: list[int], summary: RunSummary
              ) -> None:
    """Write ``out/fdir.png`` for the observers ``shown`` (module docstring)."""
    fig, axes = plt.subplots(len(shown), 1, figsize=(10, figure_height_in(len(shown))),
                             sharex=True, squeeze=False)
    for k, (ax, sc) in enumerate(zip(axes[:, 0], shown, strict=True)):
        for i, (label, (t, m)) in enumerate(margins(
                [w for w in windows if w.spacecraft == sc]).items()):
            ax.plot(t, m, "o-" if i == 0 else ".-", ms=3 if i == 0 else 2, lw=0.9,
                    color=f"C{i}", label=label if k == 0 else None)
        ax.axhline(0.0, color="k", lw=0.8, ls="--", label="threshold" if k == 0 else None)
        for f in summary.injected_faults:
            if f.spacecraft in (0, sc):
                ax.axvline(f.start_s, color="tab:red", lw=1.0)
        for d in summary.detections or []:
            if d.spacecraft in (0, sc) and d.declared_by == "ground" and d.cause is None:
                _mark(ax, d)
        ax.set_ylabel(f"sc{sc}")
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="upper left")
    axes[-1, 0].set_xlabel("sim time (s)  (red: fault onset; black: a declaration, named by "
                           "the test that declared it)")
    fig.suptitle("FDIR: each test's statistic over its threshold, log10 (fails above 0)")
    fig.tight_layout()
    fig.savefig(out / "fdir.png", dpi=110)
    plt.close(fig)


def _mark(ax: Any, d: Detection) -> None:
    """Declaration ``d`` on ``ax``: at its test's statistic over its threshold (on the
    threshold line without them), named by the test."""
    test = detection_test(d)
    y = log_margin(d.metric, d.threshold)
    ax.plot([d.time_s], [0.0 if y is None else y], "kv", ms=6)
    ax.annotate(LABELS[test].name, (d.time_s, 0.0 if y is None else y),
                textcoords="offset points", xytext=(4, 4), fontsize=7)
