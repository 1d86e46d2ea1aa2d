"""report.md of a run, with PNG plots beside it (matplotlib, no display needed)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ground.archive.segments import run_archive  # noqa: E402
from harness.archive.reader import ArchiveError, RunArchive  # noqa: E402
from harness.archive.span import seconds  # noqa: E402
from harness.destination import write_whole  # noqa: E402
from harness.report_fdir_plot import plot_fdir  # noqa: E402
from harness.report_head import head_lines  # noqa: E402
from harness.report_scale import (  # noqa: E402
    SHOWN_MOST,
    capped_rows,
    figure_height_in,
    others_line,
    shown_observers,
)
from harness.summary import RunSummary, Scores  # noqa: E402
from harness.summary.control import GncSeries  # noqa: E402
from harness.summary.coverage import Coverage  # noqa: E402
from harness.summary.declaring import LABELS  # noqa: E402
from harness.summary.digest import RunDigest, digest_run  # noqa: E402
from harness.summary.execution import cycle_slip_notes  # noqa: E402
from harness.summary.fdir import detection_test  # noqa: E402
from harness.summary.nav import NavErrors  # noqa: E402
from harness.summary.truth_table import TruthTable  # noqa: E402
from interfaces.contracts import catalogue as cat  # noqa: E402
from interfaces.contracts.messages import FdirWindow  # noqa: E402
from interfaces.contracts.scenario import Scenario  # noqa: E402


def write_report(out: Path, scenario: Scenario, mission: str | None = None,
                 digest: RunDigest | None = None,
                 settings: Mapping[str, str] | None = None) -> Path:
    """Write ``<out>/report.md`` (and its plots) from ``run.mcap`` (every segment of the
    archive) and ``summary.json``
    (``digest``: the run's archive already read for the summary, ``harness.summary.digest``;
    ``settings``: what the run was launched with beyond the scenario, as given, printed with
    its settings).  It opens on the verdict (``harness/report_head.py``)."""
    mission = mission or scenario.name
    summary = RunSummary.read(out / "summary.json")
    try:
        digest = digest or digest_run(run_archive(out), scenario, mission)
    except (ArchiveError, OSError) as e:
        lines = head_lines(scenario, summary, {}, settings) + archive_end(summary)
        return _write(out, [*lines, f"The archive could not be read: {e}"])
    archive = digest.archive
    lines = head_lines(scenario, summary, archive.metadata, settings) + archive_end(summary)
    lines += _trajectory_section(out, digest.truth)
    lines += _nav_section(out, digest.nav_errors(mission), summary)
    lines += _gnc_section(out, digest.gnc_series(scenario, mission), summary)
    lines += _coverage_section(out, digest.coverage, summary)
    lines += _fdir_section(out, archive, mission, summary)
    lines += _contact_section(summary) + _neighbours_section(summary)
    lines += _links_section(summary) + _exec_section(summary) + _incidents_section(summary)
    lines += archive_section(summary)
    return _write(out, lines)


def _write(out: Path, lines: list[str]) -> Path:
    path = out / "report.md"
    write_whole(path, "\n".join(lines) + "\n")
    return path


def _trajectory_section(out: Path, truth: TruthTable) -> list[str]:
    if not len(truth):
        return ["No truth recorded.", ""]
    r = truth.r_m  # (K, N, 3)
    fig, axes = plt.subplots(1, 2, figsize=(11, 5))
    for i, sc in enumerate(truth.spacecraft):
        axes[0].plot(r[:, i, 1], r[:, i, 0], label=f"sc{sc}")
        axes[1].plot(r[:, i, 1], r[:, i, 2], label=f"sc{sc}")
    titles = (("radial x (m)", "in-plane"), ("cross-track z (m)", "along-track / cross-track"))
    for ax, (yl, title) in zip(axes, titles, strict=True):
        ax.plot(0, 0, "k*", ms=12, label="target")
        ax.set_xlabel("along-track y (m)")
        ax.set_ylabel(yl)
        ax.set_title(title)
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
    _legend(axes[0], loc="best", fontsize=8)
    fig.suptitle("True relative trajectories (LVLH of the target)")
    fig.tight_layout()
    fig.savefig(out / "trajectories.png", dpi=110)
    plt.close(fig)
    return ["## Relative trajectories", "", "![trajectories](trajectories.png)", ""]


def _legend(ax: Any, **kw: Any) -> None:
    """``ax``'s legend, of its first ``SHOWN_MOST`` + 1 entries (one per observer and the
    target's, say) and a count of the others."""
    handles, labels = ax.get_legend_handles_labels()
    most = SHOWN_MOST + 1
    if len(labels) > most:
        handles, labels = handles[:most], [*labels[:most - 1], f"{labels[most - 1]} "
                                           f"(and {len(labels) - most} more)"]
    ax.legend(handles, labels, **kw)


def _nav_section(out: Path, errs: dict[int, NavErrors], summary: RunSummary) -> list[str]:
    if not errs:
        return ["No navigation estimates recorded.", ""]
    shown = shown_observers(errs, summary)
    fig, axes = plt.subplots(len(shown), 1, figsize=(10, figure_height_in(len(shown), 2.2, 0.0)),
                             sharex=True, squeeze=False)
    for ax, (sc, e) in zip(axes[:, 0], ((sc, errs[sc]) for sc in shown), strict=True):
        pos = np.linalg.norm(e.error[:, :3], axis=1)
        bound = 3 * np.sqrt(np.sum(e.sigma[:, :3] ** 2, axis=1))
        ax.semilogy(e.t_s, pos, lw=0.8, label="|position error|")
        ax.semilogy(e.t_s, bound, "r--", lw=0.8, label="3σ (trace)")
        ax.set_ylabel(f"sc{sc} (m)")
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("sim time (s)")
    fig.suptitle("Navigation position error against truth")
    fig.tight_layout()
    fig.savefig(out / "nav_error.png", dpi=110)
    plt.close(fig)
    rows = ["| sc | pos RMS (m) | pos max (m) | vel RMS (m/s) | "
            "mean NEES (6 dof) | NEES in 95% | mean NIS |",
            "|---|---|---|---|---|---|---|"]
    for sc, st in (summary.nav or {}).items():
        if st and int(sc) in shown:
            rows.append(f"| {sc} | {st.pos_rms_m:.3f} | {st.pos_max_m:.3f} | "
                        f"{st.vel_rms_mps:.4f} | {st.nees_mean:.2f} | "
                        f"{100 * st.nees_in_95_bounds:.0f}% | "
                        f"{st.nis_mean or float('nan'):.2f} |")
    rms = {int(sc): st.pos_rms_m for sc, st in (summary.nav or {}).items() if st}
    return ["## Navigation", "", "![nav error](nav_error.png)", "", *rows, "",
            *others_line("position error RMS", shown, rms, "m")]


def _gnc_section(out: Path, series: dict[int, GncSeries], summary: RunSummary) -> list[str]:
    if not any(s.dv_t_s or s.point_t_s for s in series.values()):
        return ["No guidance or attitude data recorded.", ""]
    fig, axes = plt.subplots(3, 1, figsize=(10, 8.5), sharex=True)
    for sc, s in series.items():
        axes[0].plot(s.dv_t_s, 1e3 * np.array(s.dv_mps), lw=1.0, label=f"sc{sc}")
        axes[1].semilogy(s.hold_t_s, np.maximum(s.hold_error_m, 1e-4), ".", ms=3, label=f"sc{sc}")
        axes[2].semilogy(s.point_t_s, np.maximum(np.degrees(s.pointing_error_rad), 1e-4), lw=0.8,
                         label=f"sc{sc}")
    axes[0].set_ylabel("Δv delivered, L1 (mm/s)")
    axes[1].set_ylabel("|r − r_PRO| holding (m)")
    axes[2].set_ylabel("pointing error (deg)")
    axes[2].set_xlabel("sim time (s)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    _legend(axes[0], loc="upper left", fontsize=8, ncol=5)
    fig.suptitle("Guidance and attitude control against truth")
    fig.tight_layout()
    fig.savefig(out / "gnc.png", dpi=110)
    plt.close(fig)

    def f(v: float | None, fmt: str) -> str:
        return "–" if v is None else format(v, fmt)

    rows = ["| sc | Δv delivered L1 (mm/s) | Δv planned L1 (mm/s) | transfers | min range (m) | "
            "hold error RMS / max (m) | pointing error mean / p95 (deg, tracking) | "
            "attitude knowledge RMS (arcsec) |", "|---|---|---|---|---|---|---|---|"]
    shown = shown_observers((int(sc) for sc in summary.gnc or {}), summary)
    for sc, g in (summary.gnc or {}).items():
        if int(sc) not in shown:
            continue
        rows.append(
            f"| {sc} | {1e3 * g.dv_delivered_l1_mps:.1f} | {1e3 * g.dv_planned_l1_mps:.1f} | "
            f"{g.transfers} | {f(g.min_range_m, '.1f')} | "
            f"{f(g.hold_error_rms_m, '.3f')} / {f(g.hold_error_max_m, '.3f')} | "
            f"{f(g.pointing_error_mean_deg, '.3f')} / {f(g.pointing_error_p95_deg, '.3f')} | "
            f"{f(g.knowledge_error_rms_arcsec, '.1f')} |")
    dv = {int(sc): 1e3 * g.dv_delivered_l1_mps for sc, g in (summary.gnc or {}).items()}
    return ["## Guidance and attitude", "", "![gnc](gnc.png)", "", *rows, "",
            *others_line("Δv delivered (L1)", shown, dv, "mm/s")]


def _coverage_section(out: Path, c: Coverage, summary: RunSummary) -> list[str]:
    if not c.h:
        return ["No camera images recorded.", ""]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    axes[0].plot(c.t_s, c.h, "k-", lw=1.2)
    axes[0].set_ylabel("information cost H (all images fused)")
    for sc, (ts, hs) in sorted(c.h_i.items()):
        axes[1].plot(ts, hs, ".-", ms=3, lw=0.8, label=f"sc{sc}")
    axes[1].set_ylabel("H_i reported (Eq. 8)")
    _legend(axes[1], fontsize=8)
    for ax in axes:
        ax.set_xlabel("sim time (s)")
        ax.grid(True, alpha=0.3)
        for d in c.decisions:  # the ground's orbit choices: solid when flown
            ax.axvline(d.t_sim, color="tab:blue", lw=0.8, ls="-" if d.switched else ":")
    fig.suptitle("Inspection: information cost")
    fig.tight_layout()
    fig.savefig(out / "coverage.png", dpi=110)
    plt.close(fig)
    cov = summary.coverage
    return ["## Inspection", "", "![coverage](coverage.png)", "",
            f"H from {cov.H_initial if cov else float('nan'):.4f} to "
            f"{cov.H_final if cov else float('nan'):.4f}; "
            f"{100 * (cov.fraction_observed if cov else 0):.1f}% of the POIs observed.", ""] \
        + _decision_rows(c)


def _decision_rows(c: Coverage) -> list[str]:
    """The ground's information-driven orbit decisions (vertical lines in the plot)."""
    if not c.decisions:
        return []
    rows = ["Orbit assignment decisions (blue lines; dotted: current set kept):", "",
            "| t (s) | phase | reason | PROs (library index per observer) | expected gain | "
            "bound ratio | current set's gain | measured gains | flown |",
            "|---|---|---|---|---|---|---|---|---|"]
    for d in c.decisions:
        cur = "-" if d.current_gain is None else f"{d.current_gain:.3g}"
        gains = ", ".join(f"{g:.3g}" for g in d.measured_gains) or "-"
        rows.append(f"| {d.t_sim:.0f} | {d.phase} | {d.reason} | {d.library_indices} | "
                    f"{d.expected_gain:.3g} | {d.ratio_bound:.3f} | {cur} | {gains} | "
                    f"{'yes' if d.switched else 'no'} |")
    return rows + [""]


def _fdir_section(out: Path, archive: RunArchive, mission: str, summary: RunSummary
                  ) -> list[str]:
    """Per observer shown (``harness/report_scale.py``): each test's statistic over its
    threshold, with each declaration named by the test that declared it
    (``harness/report_fdir_plot.py``), fault onsets and the tables."""
    windows = archive.of(cat.FDIR_WINDOW, mission)
    judged = [w for w in windows if w.metric is not None and w.threshold is not None]
    if not judged:
        return ["No FDIR decision recorded.", ""]
    ids = shown_observers({w.spacecraft for w in windows}, summary)
    plot_fdir(out, windows, ids, summary)
    _gain_plot(out, judged, ids)
    scan = _scan_plot(out, windows, ids, summary)
    hidden = len({w.spacecraft for w in windows}) - len(ids)
    note = [f"Plotted: {', '.join(f'sc{sc}' for sc in ids)}; the other {hidden} observers had "
            "no fault and no declaration.", ""] if hidden else []
    rows = ["## FDIR", "", "![fdir](fdir.png)", "", *note, "![fdir gain](fdir_gain.png)", "",
            *scan,
            "| fault | spacecraft | onset (s) | detected | isolated | latency (s) | class |",
            "|---|---|---|---|---|---|---|"]
    scores = summary.scores
    for f in scores.per_fault if scores else []:
        lat = "-" if f.latency_s is None else f"{f.latency_s:.0f}"
        rows.append(f"| {f.kind} | {f.spacecraft} | {f.start_s:.0f} | "
                    f"{'yes' if f.detected else 'no'} | {'yes' if f.isolated else 'no'} | "
                    f"{lat} | {f.identified_class or '-'} (expected {f.expected_class}) |")
    if not (scores and scores.per_fault):
        rows[-2:] = ["No fault injected."]
    rows += ["", f"False alarms: {scores.false_alarms if scores else 0} in "
                 f"{scores.nominal_cycles if scores else 0} nominal FDI cycles.", ""]
    return (rows + _identification_rows(summary) + _table4_rows(summary)
            + _detector_rows(summary) + _recovery_rows(summary))


def _mark_faults(ax: Any, sc: int, summary: RunSummary) -> None:
    """Observer ``sc``'s fault onsets (red) and declarations (dotted) on ``ax``, its label
    and grid."""
    for f in summary.injected_faults:
        if f.spacecraft == sc:
            ax.axvline(f.start_s, color="tab:red", lw=1.0)
    for d in summary.detections or []:
        if d.spacecraft == sc:
            ax.axvline(d.time_s, color="k", lw=1.0, ls=":")
    ax.set_ylabel(f"sc{sc}")
    ax.grid(True, alpha=0.3)


def _scan_plot(out: Path, windows: list[FdirWindow], ids: list[int], summary: RunSummary
               ) -> list[str]:
    """With the sequential test: per observer, the largest statistic of each window of the
    image scan and the NIS scan against their thresholds (fdir_scan.png), the report's lines
    for it (none without)."""
    scanned = [w for w in windows if w.scan_z_max is not None and w.scan_threshold is not None]
    if not scanned:
        return []
    fig, axes = plt.subplots(len(ids), 1, figsize=(10, figure_height_in(len(ids))),
                             sharex=True, squeeze=False)
    for ax, sc in zip(axes[:, 0], ids, strict=True):
        mine = [w for w in scanned if w.spacecraft == sc]
        t = [w.t_end_s for w in mine]
        ax.plot(t, [w.scan_z_max for w in mine], "o-", ms=3, lw=1.0, label="images: max |Z|")
        ax.plot(t, [w.scan_threshold for w in mine], "--", lw=1.0, label="c")
        nis = [w for w in windows if w.spacecraft == sc and w.nis_scan_z_max is not None]
        if nis:
            ax.plot([w.t_end_s for w in nis], [w.nis_scan_z_max for w in nis], "s-", ms=2,
                    lw=0.8, label="NIS: max z")
            ax.plot([w.t_end_s for w in nis], [w.nis_scan_threshold for w in nis], ":",
                    lw=1.0, label="c NIS")
        _mark_faults(ax, sc, summary)
    axes[0, 0].legend(fontsize=8, loc="upper right")
    axes[-1, 0].set_xlabel("window end, sim time (s)  (red: fault onset, dotted: declared)")
    fig.suptitle("FDIR: the sequential test's scan statistic, largest in each window, "
                 "against its threshold")
    fig.tight_layout()
    fig.savefig(out / "fdir_scan.png", dpi=110)
    plt.close(fig)
    return ["![fdir scan](fdir_scan.png)", ""]


def _identification_rows(summary: RunSummary) -> list[str]:
    """Each declared fault with the test that declared it, that test's statistic and threshold
    (named as the test names them) and the evidence its class rests on
    (ground/fdir/identify.py)."""
    rows = ["| declared (s) | spacecraft | class | declaring test | statistic | threshold | "
            "evidence |", "|---|---|---|---|---|---|---|"]
    for d in summary.detections or []:
        ev = ", ".join(f"{k} {v:.3g}" for k, v in d.evidence.items()) or "-"
        label = LABELS[detection_test(d)]
        m = "-" if d.metric is None else f"{label.statistic} {d.metric:.3g}"
        tau = "-" if d.threshold is None else f"{label.threshold} {d.threshold:.3g}"
        who = (f"neighbours {', '.join(map(str, d.judges or []))}"
               if d.declared_by == "neighbours" else d.fault_class or "unidentified")
        rows.append(f"| {d.time_s:.0f} | {d.spacecraft} | {who} | {label.name} | {m} | {tau} | "
                    f"{ev} |")
    return rows + [""] if len(rows) > 2 else []


def _recovery_rows(summary: RunSummary) -> list[str]:
    """Recovery actions and, after --compare-recovery, final H with and without them."""
    rec = summary.recovery
    acts = [d for d in (summary.coverage.assignment_decisions if summary.coverage else [])
            if d.reason == "recovery"]
    rows = [f"Recovery: {len(acts)} replan(s)"
            + "".join(f"; {d.phase} at {d.t_sim:.0f} s (PROs {d.library_indices})"
                      for d in acts) + "."]
    if rec and None not in (rec.H_final_with_recovery, rec.H_final_without_recovery):
        rows.append(f"Final H with recovery {rec.H_final_with_recovery:.5g}, without "
                    f"{rec.H_final_without_recovery:.5g} (same scenario and seed; "
                    f"{rec.counterfactual}).")
    elif rec:
        rows.append(f"The counterfactual run ({rec.counterfactual}) did not complete: "
                    f"{rec.counterfactual_status}.")
    return rows + [""]


def _table4_rows(summary: RunSummary) -> list[str]:
    """The run's row of the paper's Table 4: faulty observers, the direction their information
    gain took, whether all were detected, and the average latency."""
    per_fault = summary.scores.per_fault if summary.scores else []
    if not per_fault:
        return []
    faulty = sorted({f.spacecraft for f in per_fault})
    dirs = sorted({d.direction for d in summary.detections or []
                   if d.spacecraft in faulty and d.direction})
    lats = [f.latency_s for f in per_fault if f.isolated]
    kinds = ", ".join(sorted({f.kind for f in per_fault}))
    observed = " / ".join(f"{d} information gain" for d in dirs) or "-"
    detected = "Yes" if all(f.isolated for f in per_fault) else "No"
    latency = f"{np.mean(lats):.0f} s" if lats else "-"
    return ["Table 4 row (paper Sec. IV.B):", "",
            "| Fault | Expected signature | Observed behavior | Fault detected | Avg. latency |",
            "|---|---|---|---|---|",
            f"| {kinds} | H_m,i > 0, i = {', '.join(map(str, faulty))} | {observed} | "
            f"{detected} | {latency} |", ""]


def _detector_rows(summary: RunSummary) -> list[str]:
    """The main detector against each baseline, scored alike."""
    detectors: dict[str, Scores | None] = {"information FDIR (this)": summary.scores,
                                           **(summary.baselines or {})}
    rows = ["Detectors side by side (same run, same scoring):", "",
            "| detector | faults detected | isolated | latencies (s) | false alarms | "
            "nominal cycles |", "|---|---|---|---|---|---|"]
    for name, sc in detectors.items():
        pf = sc.per_fault if sc else []
        lats = ", ".join("-" if f.latency_s is None else f"{f.latency_s:.0f}" for f in pf)
        rows.append(f"| {name} | {sum(f.detected for f in pf)}/{len(pf)} | "
                    f"{sum(f.isolated for f in pf)}/{len(pf)} | {lats or '-'} | "
                    f"{sc.false_alarms if sc else 0} | {sc.nominal_cycles if sc else 0} |")
    return rows + [""]


def _gain_plot(out: Path, judged: list[FdirWindow], ids: list[int]) -> None:
    """Per observer, the information it actually brought (Σ ΔH_i over the judged windows)
    against what its nominal twin predicted for the same images (Σ ΔH_i^pred), as the paper's
    Fig. 23-26, left."""
    fig, ax = plt.subplots(figsize=(10, 4))
    for k, sc in enumerate(ids):
        mine = [w for w in judged if w.spacecraft == sc and w.dh is not None
                and w.dh_pred is not None]
        if not mine:
            continue
        t = [w.t_end_s for w in mine]
        color = f"C{k % 10}"
        ax.plot(t, np.cumsum([w.dh for w in mine]), "-", color=color, lw=1.2, label=f"sc{sc}")
        ax.plot(t, np.cumsum([w.dh_pred for w in mine]), "--", color=color, lw=1.0)
    ax.set_xlabel("sim time (s)")
    ax.set_ylabel("Σ ΔH_i (solid) and Σ ΔH_i^pred (dashed)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.suptitle("Information brought by each observer against its nominal twin")
    fig.tight_layout()
    fig.savefig(out / "fdir_gain.png", dpi=110)
    plt.close(fig)


def _contact_section(summary: RunSummary) -> list[str]:
    """The pass table and the onboard stores (runs with ground passes)."""
    g = summary.ground_contact
    if g is None:
        return []
    rows = ["## Ground passes", "",
            f"The ground hears only in passes; longest gap {g.longest_gap_s:.0f} s. Downlink "
            f"{g.downlink_bps / 1e6:g} Mbit/s per spacecraft, store {g.store_bytes / 2**20:g} "
            "MiB.", "",
            "| station | AOS (s) | LOS (s) | duration (s) | max elevation (°) |",
            "|---|---|---|---|---|"]
    rows += [f"| {p.station} | {p.aos_s:.0f} | {p.los_s:.0f} | {p.duration_s:.0f} | "
             f"{p.max_elevation_deg:.1f} |" for p in g.passes]
    rows += ["", "| spacecraft | stored | dumped | sent again | overflow | aboard at end | "
             "uplinks held |", "|---|---|---|---|---|---|---|"]
    for node, s in sorted(g.stores.items()):
        lost = ", ".join(f"{r.topic} {r.first_s:.0f}-{r.last_s:.0f} s ({r.count})"
                         for r in s.overflow_runs[:5]) or "none"
        aboard = (f"{s.onboard} (sent from {s.onboard_since_s:.0f} s)"
                  if s.onboard_since_s is not None else str(s.onboard))
        rows.append(f"| {node} | {s.stored} | {s.dumped} | {s.retransmitted} | {s.overflow}: "
                    f"{lost} | {aboard} | {g.uplink_held.get(node, 0)} |")
    return rows + [""]


def _neighbours_section(summary: RunSummary) -> list[str]:
    """The neighbours' FDIR aboard: its declarations with the ground's rulings, its figures
    and where it and the ground disagreed (docs/fdir.md, "Neighbours judge each other")."""
    nb = summary.neighbours
    if nb is None:
        return []
    w, d, s = nb.windows, nb.disagreements, nb.scores
    rows = ["## Neighbours' FDIR", "",
            f"{w.neighbour_windows} neighbour-windows decided ({w.judge_windows} judges' "
            f"verdicts; {w.nominal_exceeded} of {w.nominal_judge_windows} on a healthy "
            f"neighbour failed). False alarms: {s.false_alarms} in {s.nominal_cycles} nominal "
            f"neighbour-windows. Agreement: at least {nb.agree} and more than half of those "
            "that decided (one when only one did).", "",
            f"The ground upheld {d.upheld}, overruled {d.overruled}, had not ruled on "
            f"{d.unruled}; it declared {d.ground_only} spacecraft the neighbours had not.", "",
            "| window end (s) | declared (s) | spacecraft | judges | ground's ruling |",
            "|---|---|---|---|---|"]
    for det in summary.detections or []:
        if det.declared_by == "neighbours":
            ruling = nb.rulings.get(f"{det.spacecraft}@{det.time_s:g}", "-")
            rows.append(f"| {det.time_s:.0f} | {det.declared_s or 0:.0f} | {det.spacecraft} | "
                        f"{', '.join(map(str, det.judges or []))} | {ruling} |")
    return rows + [""]


def _links_section(summary: RunSummary) -> list[str]:
    rows = ["## Links", "",
            "| link | sent | delivered | dropped (range) | dropped (loss) | dropped (cut) |",
            "|---|---|---|---|---|---|"]
    links = summary.links or []
    body = [f"| {c.src} → {c.dst} | {c.sent} | {c.delivered} | {c.dropped_range} | "
            f"{c.dropped_loss} | {c.dropped_cut} |" for c in links]
    dropped = [c.dropped_range + c.dropped_loss + c.dropped_cut for c in links]
    return rows + capped_rows(body, lambda i: dropped[i], "links") + [""]


def _incidents_section(summary: RunSummary) -> list[str]:
    """Processes lost from the lockstep and telemetry outages (a degraded run), and what the
    onboard FDIR did."""
    onboard = _onboard_lines(summary)
    lost = summary.sim.participants if summary.sim else {}
    outages = {e.spacecraft: e.outages for e in summary.telemetry or []}
    if not lost and not any(outages.values()):
        return ["## Incidents", "", *onboard] if onboard else []
    rows = ["## Incidents", "", f"Run status: **{summary.status}**"
            + (f" ({summary.error})" if summary.error else ""), "",
            "| node | lockstep (sim s) | telemetry outages (sim s) |", "|---|---|---|"]
    nodes = sorted(set(lost) | {f"sc{sc}" for sc, o in outages.items() if o})
    for node in nodes:
        events = ", ".join(f"{e.what} {e.t_sim:.1f}" for e in lost.get(node, []))
        sc = int(node[2:]) if node.startswith("sc") else None
        gaps = ", ".join(f"{a:.1f}-{b:.1f}" for a, b in outages.get(sc, []))
        rows.append(f"| {node} | {events or '-'} | {gaps or '-'} |")
    return rows + [""] + onboard


def _onboard_lines(summary: RunSummary) -> list[str]:
    """What the onboard FDIR did (fsw/apps/fdir.py): per injected fault, then every event."""
    ob = summary.onboard_fdir
    if ob is None:
        return []

    def at(v: float | None) -> str:
        return "-" if v is None else f"{v:.1f}"

    rows = ["### Onboard FDIR", "",
            f"{ob.trips} watchpoint trips, {ob.reports} ground reports received, {ob.actions} "
            f"stored sequences started, {ob.recoveries} safe holds ended by a new assignment.",
            ""]
    if ob.per_fault:
        rows += ["| fault | onset | ground detected | class (at) | report received | action (at) "
                 "| first trip (at): its action |", "|---|---|---|---|---|---|---|"]
        rows += [f"| sc{f.spacecraft} {f.kind} | {f.start_s:.0f} | {at(f.detected_s)} | "
                 f"{f.identified_class or '-'} ({at(f.identified_s)}) | "
                 f"{at(f.report_received_s)} | {f.action or '-'} ({at(f.action_s)}) | "
                 f"{f.trip or '-'} ({at(f.trip_s)}): {f.trip_action or '-'} |"
                 for f in ob.per_fault]
        rows.append("")
    if ob.events:
        rows += ["| t (s) | sc | event | name | value / limit | detail |",
                 "|---|---|---|---|---|---|"]
        rows += [f"| {e.t_sim:.1f} | {e.spacecraft} | {e.event} | {e.name} | "
                 + (f"{e.value:.3g} / {e.limit:.3g}" if e.value is not None and e.limit else "-")
                 + f" | {e.detail} |" for e in ob.events]
        rows.append("")
    return rows


def archive_section(summary: RunSummary) -> list[str]:
    """The archive's segments (a restarted recorder) and the messages lost, by topic; nothing
    for a run archived whole in one file."""
    info = summary.archive
    if info is None or info.segments is None or info.lost is None:
        return []
    files = ", ".join(s.file + (" (truncated)" if s.truncated else "") for s in info.segments)
    rows = ["## Archive", "", f"Segments: {files}.", "",
            f"Messages lost (sent, never archived): {info.lost.total}.", ""]
    if info.lost.by_topic:
        rows += ["| topic | lost |", "|---|---|",
                 *(f"| {t} | {n} |" for t, n in info.lost.by_topic.items()), ""]
    return rows


def archive_end(summary: RunSummary) -> list[str]:
    """Where an archive that ends before its run does, and why; nothing for a whole one."""
    info, duration_s = summary.archive, summary.duration_s
    if info is None or info.end_s is None:
        return []
    run = f" of the run's {seconds(duration_s)} s" if duration_s is not None else ""
    cut = f" ({info.cut})" if info.cut else ""
    return [f"The archive ends at {seconds(info.end_s)} s{run}{cut}: this report covers what "
            "it holds, nothing after.", ""]


def _exec_section(summary: RunSummary) -> list[str]:
    rows = ["## Executives", "",
            "| node | cycle slips (high/mid/low) | max exec ms (high/mid/low) | app errors "
            "| invalid msgs | refused msgs | barrier timeouts |",
            "|---|---|---|---|---|---|---|"]
    body, trouble = [], []
    for node, e in (summary.exec or {}).items():
        slips = "/".join(str(e.cycle_slips.get(g, 0)) for g in ("high", "mid", "low"))
        ms = "/".join(f"{e.max_exec_ms.get(g, 0):.2f}" for g in ("high", "mid", "low"))
        body.append(f"| {node} | {slips} | {ms} | {e.app_errors} | {e.invalid_dropped} | "
                    f"{e.refused} | {e.barrier_timeouts} |")
        trouble.append(sum(e.cycle_slips.values()) + e.app_errors + e.invalid_dropped
                       + e.refused + e.barrier_timeouts + (0 if node.startswith("sc") else 1))
    return (rows + capped_rows(body, lambda i: trouble[i], "nodes") + [""]
            + cycle_slip_notes(summary.exec))
