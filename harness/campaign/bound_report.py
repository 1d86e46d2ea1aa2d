"""The campaign report's "Delay against the bound" section (issue 41; docs/fdir.md, "The
bound"): where the sequential test ran, each fault kind's measured delay beside the smallest
delay any test as quick to false-alarm could have, log γ / D (``harness/summary/delay_bound.py``
computes each fault's D and bound; results.csv's ``image_divergence``, ``delay_bound_s``).

The delay is the main detector's from the fault's first judgeable window (``window_latency_s``:
from onset for a fault that starts while its observer is judged), to the first isolating
alarm, whichever test declared it (``declaring_test``).  A table per kind and a plot,
bound.png: each fault's delay against its magnitude, its bound beneath it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

WITHIN = 2.0
"""The factor of the bound a delay is judged against (issue 41: "within 2×")."""

MARKERS = {"sequential": ("o", "C0"), "nis_scan": ("s", "C2"), "pointing_scan": ("D", "C3")}
"""The plot's marker and colour by what declared a fault (a window's tests: a triangle)."""


def bounded_rows(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The main detector's isolated faults with a delay and a bound."""
    return [r for r in rows if r["detector"] == "main" and r["kind"] != "none"
            and r.get("delay_bound_s") is not None and r["isolated"]
            and r.get("window_latency_s") is not None]


def kind_figures(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """One kind's figures over its :func:`bounded_rows`: counts by declaring test, medians of
    the delay, the bound and D, and how many delays are within ``WITHIN`` × the bound."""
    delay = np.array([r["window_latency_s"] for r in rows], dtype=float)
    bound = np.array([r["delay_bound_s"] for r in rows], dtype=float)
    nis = [r["nis_divergence"] for r in rows if r.get("nis_divergence") is not None]
    return {"faults": len(rows),
            "scan": sum(r.get("declaring_test") == "sequential" for r in rows),
            "nis_scan": sum(r.get("declaring_test") == "nis_scan" for r in rows),
            "pointing_scan": sum(r.get("declaring_test") == "pointing_scan" for r in rows),
            "delay": float(np.median(delay)), "bound": float(np.median(bound)),
            "divergence": float(np.median([r["image_divergence"] for r in rows])),
            "nis": float(np.median(nis)) if nis else None,
            "within": int(np.sum(delay <= WITHIN * bound))}


def bound_lines(out: Path, rows: list[dict[str, Any]]) -> list[str]:
    """The section's lines (none where the sequential test did not run), and bound.png."""
    bounded = bounded_rows(rows)
    if not bounded:
        return []
    kinds = sorted({r["kind"] for r in bounded})
    lines = ["", "## Delay against the bound (sequential test)", "",
             "Per fault: D = δ²/2σ² nats per image (δ: the observer's mean relative shift of "
             "ΔH/ΔH^pred over its first whole window after onset; σ: one image's nominal 1σ), "
             "D of the NIS per update, 3(λ − 1) (λ: the window's mean NIS over its 6 "
             "degrees), and the bound: when the divergence summed step by step from the onset "
             "(the image's D each step, each nav update's (NIS − 6)/2) first reaches log γ "
             "(γ: the scans' mean time to a false alarm), at least one step. Delay: from the "
             "first "
             "judgeable window (from onset for a fault that starts while its observer is "
             "judged) to the first isolating alarm, by any test. Medians.", "",
             "![bound](bound.png)", "",
             f"| kind | faults | declared by the image scan / NIS scan / pointing run / a "
             f"window | delay (s) | "
             f"bound (s) | D ratio (nats) | D NIS (nats) | within {WITHIN:.0f}× |",
             "|---|---|---|---|---|---|---|---|"]
    for kind in kinds:
        st = kind_figures([r for r in bounded if r["kind"] == kind])
        nis = "-" if st["nis"] is None else f"{st['nis']:.3g}"
        windows = st["faults"] - st["scan"] - st["nis_scan"] - st["pointing_scan"]
        lines.append(f"| {kind} | {st['faults']} | {st['scan']} / {st['nis_scan']} / "
                     f"{st['pointing_scan']} / {windows} | "
                     f"{st['delay']:.0f} | "
                     f"{st['bound']:.1f} | {st['divergence']:.3g} | {nis} | "
                     f"{st['within']} of {st['faults']} |")
    _bound_plot(out, bounded, kinds)
    return lines


def _bound_plot(out: Path, rows: list[dict[str, Any]], kinds: list[str]) -> None:
    """Per kind: each fault's delay (``MARKERS``: what declared it) over its magnitude, a
    line down to its bound (cross)."""
    fig, axes = plt.subplots(1, len(kinds), figsize=(3.6 * len(kinds), 3.8), squeeze=False)
    for ax, kind in zip(axes[0], kinds, strict=True):
        mine = [r for r in rows if r["kind"] == kind]
        for r in mine:
            x, delay = r["magnitude"] or 0.0, max(r["window_latency_s"], 0.5)
            ax.plot([x, x], [r["delay_bound_s"], delay], "-", color="0.7", lw=0.8)
            ax.plot(x, r["delay_bound_s"], "x", color="0.3", ms=5)
            marker, colour = MARKERS.get(r.get("declaring_test"), ("^", "C1"))
            ax.plot(x, delay, marker, color=colour, ms=4)
        ax.set_yscale("log")
        ax.set_title(kind, fontsize=9)
        ax.set_xlabel("magnitude")
        ax.grid(True, alpha=0.3, which="both")
    axes[0][0].set_ylabel("delay (s): o image scan, s NIS scan, ◆ pointing run, ^ window; "
                          "x bound")
    fig.suptitle("delay against the information bound, per fault kind")
    fig.tight_layout()
    fig.savefig(out / "bound.png", dpi=100)
    plt.close(fig)
