"""Campaign report, rendered: detection, latency, false-alarm, isolation and identification
figures over many runs, for the main detector and each baseline side by side (issue 6;
docs/contracts.md "Campaigns"), as Markdown, CSV and plots.  The figures themselves, and the
re-scoring under other rules, are computed in ``harness/campaign/rescore.py``.

Reads ``<out>/runs/<id>/summary.json`` of every run and writes ``<out>/results.csv`` (one row
per injected fault and detector, plus one per nominal run and detector), ``<out>/report.md``
(figures over all runs, per campaign group, by each dimension a campaign drew per run --
``harness/campaign/dimensions.py``, also in ``<out>/dimensions.json`` -- per fault kind and
magnitude) and its plots:
latency distributions per group, the confusion matrix of identified class against
injected kind, and a ROC curve per detector from sweeping a scale on its threshold
(re-scored from each run's ``fdir_series`` with the detector's persistence), a table of
the main detector re-scored under other persistence rules (m of the last n windows), and the
distribution of its H_m,i / τ_i in nominal windows and in windows of each fault kind.

Definitions as in harness/summary/scoring.py: a fault is detected when any alarm falls in its
active span (plus one FDI window), isolated when one names its spacecraft; a false alarm is
an alarm on a spacecraft with no active fault; rates are per nominal FDI cycle and per hour.
"""

from __future__ import annotations

import csv
import functools
import json
import math
import operator
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from harness.campaign.bound_report import bound_lines  # noqa: E402
from harness.campaign.dimensions import BinFigures, Dimension, by_dimension  # noqa: E402
from harness.campaign.rescore import (  # noqa: E402
    PERSISTENCE_RULES,
    SCALES,
    CampaignRun,
    detector_stats,
    fault_rows,
    information_only,
    load_runs,
    nominal_hours,
    persistence_of,
    rescore,
    roc,
    spread,
    window_margins,
)
from harness.campaign.targets import (  # noqa: E402
    noted_rate,
    rate,
    share,
    target_figures,
    target_lines,
)
from harness.destination import write_whole  # noqa: E402
from harness.summary.scoring import EXPECTED_CLASS  # noqa: E402

CLASSES = ("actuator", "camera", "state_sensor", "link", "data_integrity", "common_mode", None)


def _versions(runs: list[CampaignRun]) -> str:
    counts: dict[str, int] = {}
    for r in runs:
        counts[r.version] = counts.get(r.version, 0) + 1
    text = ", ".join(f"{v} ({n} runs)" for v, n in sorted(counts.items()))
    return f"Software: {text}" + (" -- MIXED: results may not be comparable." if len(counts) > 1
                                  else ".")


def _wall_time(runs: list[CampaignRun]) -> str:
    """The runs' own wall time (one worker each, from summary.json ``wall_s``)."""
    wall = [r.summary.wall_s for r in runs if r.summary.wall_s is not None]
    if not wall:
        return "Run wall time: not recorded."
    return (f"Run wall time (each on one worker): median {np.median(wall):.0f} s, max "
            f"{max(wall):.0f} s, {sum(wall) / 3600.0:.2f} worker-hours in all.")


def _cells(detector: str, st: dict[str, Any]) -> str:
    """The table cells after the row's labels: detected, isolated, identified (main only),
    latency median / p90 / max, false alarms per nominal cycle and per hour."""
    ident = share(st["identified"], st["faults"]) if detector == "main" else "-"
    return (f"{share(st['detected'], st['faults'])} | {share(st['isolated'], st['faults'])} | "
            f"{ident} | {st['latency']} | {rate(st['false_alarms'], st['nominal_cycles'])} | "
            f"{_fmt(st['false_alarms_per_hour'], '.3f')} |")


def _fmt(v: float | None, f: str = ".0f") -> str:
    return "-" if v is None else format(v, f)


def _persistence_table(runs: list[CampaignRun]) -> list[str]:
    """The main detector re-scored from its windows under each of ``PERSISTENCE_RULES``, at
    its threshold as configured: what persistence buys in false alarms and costs in latency."""
    own = sorted({persistence_of(r.summary, "main") for r in runs})
    lines = ["| rule | detected | isolated | latency median / p90 / max (s) | "
             "false alarms per nominal cycle |", "|---|---|---|---|---|"]
    for m, n in PERSISTENCE_RULES:
        r = rescore(runs, "main", 1.0, (m, n))
        f = r.per_fault
        label = f"{m} of {n}" + (" (as run)" if own == [(m, n)] else "")
        lat = [x.latency_s for x in f if x.isolated and x.latency_s is not None]
        lines.append(
            f"| {label} | {share(sum(x.detected for x in f), len(f))} | "
            f"{share(sum(x.isolated for x in f), len(f))} | {spread(lat)} | "
            f"{rate(r.false_alarms, r.nominal_cycles)} |")
    return lines


RESULT_FIELDS = ["run", "group", "seed", "status", "detector", "kind", "spacecraft", "start_s",
                 "magnitude", "detected", "isolated", "latency_s", "identified_class",
                 "identification_latency_s", "expected_class", "judgeable_s", "unjudged",
                 "window_latency_s", "declared_latency_s", "contact", "neighbours_latency_s",
                 "first_latency_s", "declaring_test", "image_divergence", "nis_divergence",
                 "delay_bound_s",
                 "false_alarms", "nominal_cycles"]
"""The columns of results.csv."""


def write_campaign_report(out: Path, name: str, ids: Sequence[str]) -> Path:
    """Write results.csv, report.md and plots for the runs ``ids`` of campaign ``name``."""
    loaded = load_runs(out, ids)
    runs = [r for r in loaded if r.summary.status == "completed"]  # failed runs: listed only
    rows = fault_rows(runs)
    with open(out / "results.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=RESULT_FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    detectors = ["main"] + sorted({r["detector"] for r in rows} - {"main"})
    hours = {d: nominal_hours(runs, d) for d in detectors}
    lines = _head_lines(name, loaded, len(ids), hours["main"]) + settings_lines(out)
    lines += target_lines(target_figures(rows, runs))
    lines += _side_by_side_lines(rows, detectors, hours)
    groups = list(dict.fromkeys(r.group for r in runs))
    lines += _group_lines(runs, rows, detectors, groups)
    lines += _dimension_lines(out, by_dimension(loaded, rows))
    lines += _magnitude_lines(rows, detectors, hours)
    lines += bound_lines(out, rows)
    lines += _identification_lines(out, rows, hours["main"])
    lines += _rescoring_lines(runs)
    lines += _threshold_lines(runs)
    margins = window_margins(runs)
    lines += ["", "## Margins (main detector, H_m,i / τ_i per window)", "",
              "![margins](margins.png)", ""] + _margin_lines(margins)
    _latency_plot(out, rows, detectors, [g for g in groups
                                         if any(r["group"] == g and r["kind"] != "none"
                                                for r in rows)])
    _roc_plot(out, runs, detectors)
    _margin_plot(out, margins)
    path = out / "report.md"
    write_whole(path, "\n".join(lines) + "\n")
    return path


def _head_lines(name: str, loaded: list[CampaignRun], requested: int,
                main_hours: float) -> list[str]:
    """The title, the runs finished and failed, software versions and wall time."""
    failed = [r.id for r in loaded if r.summary.status != "completed"]
    return [f"# Campaign report: {name}", "",
            f"{len(loaded)} of {requested} runs finished ({len(failed)} failed"
            + (f": {', '.join(failed[:10])}{' ...' if len(failed) > 10 else ''}" if failed
               else "") + "; failed runs are left out of every figure below); "
            f"{main_hours:.1f} nominal spacecraft-hours judged by the main detector.", "",
            _versions(loaded), "", _wall_time(loaded), ""]


def settings_lines(out: Path) -> list[str]:
    """The settings the campaign's runs were made with, from ``<out>/campaign.json``: those
    given with ``--set`` over the campaign file's (or a replay's), and the campaign replayed;
    nothing without the file."""
    index = out / "campaign.json"
    if not index.exists():
        return []
    meta = json.loads(index.read_text())
    given = meta.get("settings") or {}
    text = ", ".join(f"{k} = {v}" for k, v in given.items())
    source = f"replay of {meta['replay_of']}: " if meta.get("replay_of") else ""
    return [f"Settings: {source}"
            + (f"{text} (--set, over each run's own)." if text else
               "each run's own, nothing set over them (no --set)."), ""]


def _side_by_side_lines(rows: list[dict[str, Any]], detectors: list[str],
                        hours: dict[str, float]) -> list[str]:
    lines = ["## Detectors side by side", "",
             "| detector | detected | isolated | identified | latency median / p90 / max (s) | "
             "false alarms per nominal cycle | per hour |", "|---|---|---|---|---|---|---|"]
    for d in detectors:
        lines.append(f"| {d} | " + _cells(d, detector_stats([r for r in rows if r["detector"] == d],
                                                      hours[d])))
    return lines


def _group_lines(runs: list[CampaignRun], rows: list[dict[str, Any]], detectors: list[str],
                 groups: list[str]) -> list[str]:
    lines = ["", "## Per campaign group", "",
             "Each group of the campaign file (in paper.toml, one per paper figure); false "
             "alarms are those on the group's unfaulted spacecraft.", "",
             "| group | detector | detected | isolated | identified | latency median / p90 / "
             "max (s) | false alarms per nominal cycle | per hour |",
             "|---|---|---|---|---|---|---|---|"]
    for g in groups:
        mine = [r for r in runs if r.group == g]
        for d in detectors:
            st = detector_stats([r for r in rows if r["detector"] == d and r["group"] == g],
                        nominal_hours(mine, d))
            lines.append(f"| {g} | {d} | " + _cells(d, st))
    return lines


def _dimension_lines(out: Path, dimensions: list[Dimension]) -> list[str]:
    """"By drawn dimension": one table per dimension the campaign drew (none if it drew
    nothing), also written to ``dimensions.json``."""
    if not dimensions:
        return []
    (out / "dimensions.json").write_text(json.dumps(
        {d.name: d.to_json() for d in dimensions}, indent=1) + "\n")
    lines = ["", "## By drawn dimension", "",
             "Each setting the campaign drew per run, its runs in bins (a choice: by value; a "
             "range: four equal-width bins over its [min, max], an integer range of up to four "
             "values by value); main detector. Faults no window could judge are counted apart "
             "(unjudged); detected, identified and latencies are over the others: latency of "
             "the isolated faults from the first judgeable window, and its median from onset "
             "to the ground's declaration; false alarms per nominal observer-window and the "
             "neighbours' per nominal neighbour-window, with their 95% upper bounds. The worst "
             "bin (the largest share of failed runs, then the fewest isolated, identified, then "
             "the highest false-alarm bound, then the longest p90) is in bold "
             "(harness/campaign/dimensions.py)."]
    for d in dimensions:
        lines += ["", f"### {d.name}", "",
                  "| bin | runs | failed | faults | unjudged | detected & isolated | identified | "
                  "latency from the window, median / p90 (s) | from onset, median (s) | "
                  "false alarms per observer-window | neighbours' false alarms per "
                  "neighbour-window |", "|---|---|---|---|---|---|---|---|---|---|---|"]
        lines += [_bin_row(b) for b in d.bins]
    return lines


def _bin_row(b: BinFigures) -> str:
    label = f"**{b.label}** (worst)" if b.worst else b.label
    return (f"| {label} | {b.runs} | {b.failed} | {b.faults} | {b.unjudged} | "
            f"{share(b.isolated, b.judgeable)} | {share(b.identified, b.judgeable)} | "
            f"{_fmt(b.latency_median_s)} / {_fmt(b.latency_p90_s)} | "
            f"{_fmt(b.onset_latency_median_s)} | {noted_rate(b.false_alarms, b.windows)} | "
            f"{noted_rate(b.neighbour_false_alarms, b.neighbour_windows)} |")


def _magnitude_lines(rows: list[dict[str, Any]], detectors: list[str],
                     hours: dict[str, float]) -> list[str]:
    lines = ["", "## Per fault kind and magnitude", "",
             "| kind | magnitude | detector | faults | detected | missed | isolated | "
             "latency median / p90 / max (s) |", "|---|---|---|---|---|---|---|---|"]
    bins = magnitude_bins([r for r in rows if r["kind"] != "none" and r["detector"] == "main"])
    for (kind, label), members in bins.items():
        for d in detectors:
            sel = [r for r in rows if r["detector"] == d and r["kind"] == kind
                   and (r["run"], r["fault_index"]) in members]
            st = detector_stats(sel, hours[d])
            lines.append(f"| {kind} | {label} | {d} | {st['faults']} | "
                         f"{share(st['detected'], st['faults'])} | "
                         f"{st['faults'] - st['detected']} | "
                         f"{share(st['isolated'], st['faults'])} | {st['latency']} |")
    return lines


def _identification_lines(out: Path, rows: list[dict[str, Any]], main_hours: float
                          ) -> list[str]:
    """The main detector's identification (confusion matrix) and its latency from onset."""
    main_stats = detector_stats([r for r in rows if r["detector"] == "main"], main_hours)
    lines = ["", "## Identification (main detector)", "",
             "Identification may come a window after detection: latency from onset to the "
             f"first report naming the right class, median / p90 / max: "
             f"{main_stats['identification_latency']} s.", "",
             "![confusion](confusion.png)", ""]
    main_faults = [r for r in rows if r["detector"] == "main" and r["kind"] != "none"]
    return lines + _confusion(out, main_faults)


def _rescoring_lines(runs: list[CampaignRun]) -> list[str]:
    """The ROC and the main detector re-scored under other persistence rules, saying when
    summaries predate the other tests' record."""
    lines = ["", "![latency](latency.png)", "",
             "## ROC (threshold scale swept, each detector with its persistence)", "",
             "![roc](roc.png)", "",
             "## Persistence (main detector re-scored from its windows)", "",
             "A fault is declared on the window that brings the exceedances among the last n "
             "windows to m; the threshold as configured.  A main-detector window counts as "
             "exceeded when H_m passes τ or it failed one of the other tests (plan, pointing, "
             "Δv rate, NIS), which the ROC's scale does not move."]
    old_rows = information_only(runs)
    if old_rows:
        lines.append(f"**{old_rows} of {len(runs)} runs' summaries predate the other tests' "
                     "record: in them the main detector's ROC and this table see the "
                     "information test alone, and undercount what it detected.**")
    return lines + [""] + _persistence_table(runs)


def magnitude_bins(rows: list[dict[str, Any]], most: int = 4
                    ) -> dict[tuple[str, str], set[tuple[str, int]]]:
    """Faults grouped by kind and magnitude, in kind then magnitude order: each distinct
    magnitude when a kind has at most ``most`` of them, else three equal-width bins (dispersed
    magnitudes).  Values: the (run, fault index) of the faults in the group."""
    keyed: dict[tuple[str, float, str], set[tuple[str, int]]] = {}
    for kind in sorted({r["kind"] for r in rows}):
        mine = [r for r in rows if r["kind"] == kind]
        mags = sorted({r["magnitude"] for r in mine if r["magnitude"] is not None})
        for r in mine:
            m = r["magnitude"]
            if m is None or len(mags) <= most:
                key = (kind, -math.inf if m is None else m, _fmt(m, "g"))
            else:
                lo, hi = mags[0], mags[-1]
                k = min(2, int(3 * (m - lo) / (hi - lo)))
                a, b = lo + k * (hi - lo) / 3, lo + (k + 1) * (hi - lo) / 3
                key = (kind, float(k), f"{a:.4g}–{b:.4g}")
            keyed.setdefault(key, set()).add((r["run"], r["fault_index"]))
    return {(kind, label): v for (kind, _, label), v in sorted(keyed.items())}


def _confusion(out: Path, rows: list[dict[str, Any]]) -> list[str]:
    kinds = sorted({r["kind"] for r in rows})
    m = np.zeros((len(kinds), len(CLASSES)), dtype=int)
    for r in rows:
        m[kinds.index(r["kind"]), CLASSES.index(r["identified_class"])
          if r["identified_class"] in CLASSES else len(CLASSES) - 1] += 1
    labels = [c or "none/missed" for c in CLASSES]
    out_lines = ["| injected \\ identified | " + " | ".join(labels) + " |",
                 "|---|" + "---|" * len(labels)]
    for k, row in zip(kinds, m, strict=True):
        out_lines.append(f"| {k} (→ {EXPECTED_CLASS[k]}) | " + " | ".join(map(str, row)) + " |")
    if not kinds:
        return out_lines + ["", "(no fault injected)"]
    fig, ax = plt.subplots(figsize=(8, 0.5 * max(len(kinds), 2) + 2))
    ax.imshow(m, cmap="Blues")
    ax.set_xticks(range(len(labels)), labels, rotation=30, ha="right")
    ax.set_yticks(range(len(kinds)), kinds)
    for (i, j), v in np.ndenumerate(m):
        ax.text(j, i, str(v), ha="center", va="center")
    ax.set_title("identified class against injected kind")
    fig.tight_layout()
    fig.savefig(out / "confusion.png", dpi=100)
    plt.close(fig)
    return out_lines


def _latency_plot(out: Path, rows: list[dict[str, Any]], detectors: list[str],
                  groups: list[str]) -> None:
    """Latency from onset to isolation: one box per detector (coloured) within each campaign
    group, with the number of faults each detector missed (did not isolate) under it."""
    fig, ax = plt.subplots(figsize=(max(8.0, 1.0 + 0.6 * len(detectors) * len(groups)), 4.5))
    width = 0.8 / max(len(detectors), 1)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for j, d in enumerate(detectors):
        pos, data, missed = [], [], []
        for i, g in enumerate(groups):
            faults = [r for r in rows if r["detector"] == d and r["group"] == g
                      and r["kind"] != "none"]
            lat = [r["latency_s"] for r in faults if r["isolated"] and r["latency_s"] is not None]
            pos.append(i + (j - (len(detectors) - 1) / 2) * width)
            data.append(lat or [math.nan])
            missed.append(len(faults) - len(lat))
        c = colours[j % len(colours)]
        if not groups:
            break  # no fault was injected: an empty plot
        ax.boxplot(data, positions=pos, widths=0.9 * width, patch_artist=True,
                   boxprops={"facecolor": c, "alpha": 0.6}, medianprops={"color": "k"},
                   flierprops={"markersize": 3})
        for x, m in zip(pos, missed, strict=True):
            ax.annotate(f"{m}", (x, 0), xycoords=("data", "axes fraction"),
                        xytext=(0, 3), textcoords="offset points", ha="center", fontsize=7,
                        color=c)
        ax.plot([], [], "s", color=c, alpha=0.6, label=d)
    ax.set_xticks(range(len(groups)), groups, rotation=15, ha="right")
    ax.set_xlim(-0.6, len(groups) - 0.4)
    ax.set_ylabel("latency, onset to isolation (s)")
    ax.set_title("detection latency per campaign group (numbers at the foot: faults missed)")
    if groups:
        ax.legend(fontsize=8, ncols=len(detectors))
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "latency.png", dpi=100)
    plt.close(fig)


def _roc_plot(out: Path, runs: list[CampaignRun], detectors: list[str]) -> None:
    fig, ax = plt.subplots(figsize=(6, 5))
    for d in detectors:
        fa, det = roc(runs, d)
        ax.plot(fa, det, "o-", ms=2, label=d)
        k = int(np.argmin(np.abs(SCALES - 1.0)))
        ax.plot(fa[k], det[k], "k*", ms=8)
    ax.set_xscale("symlog", linthresh=1e-3)
    ax.set_xlabel("false alarms per nominal FDI cycle")
    ax.set_ylabel("detection rate")
    ax.set_title("ROC (star: threshold as configured)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "roc.png", dpi=100)
    plt.close(fig)


def _margin_lines(margins: dict[str, np.ndarray]) -> list[str]:
    lines = ["| windows | count | median | p99 | max | share over the threshold |",
             "|---|---|---|---|---|---|"]
    for kind, r in margins.items():
        lines.append(f"| {kind} | {len(r)} | {np.median(r):.3g} | {np.quantile(r, 0.99):.3g} | "
                     f"{r.max():.3g} | {share(int(np.sum(r > 1.0)), len(r))} |")
    return lines


def _margin_plot(out: Path, margins: dict[str, np.ndarray]) -> None:
    """Histograms of H_m,i / τ_i (log scale) for nominal windows and for windows with each
    kind of fault active, with the threshold at 1."""
    fig, ax = plt.subplots(figsize=(8, 4))
    bins = np.logspace(-4, 3, 71)
    for kind, r in margins.items():
        ax.hist(np.clip(r, bins[0], bins[-1]), bins=bins, histtype="step", lw=1.5,
                label=f"{kind} ({len(r)})", weights=np.full(len(r), 1.0 / len(r)))
    ax.axvline(1.0, color="k", ls="--", lw=1)
    ax.set_xscale("log")
    ax.set_xlabel("H_m,i / τ_i  (a window over 1 exceeds its threshold)")
    ax.set_ylabel("share of the windows")
    ax.set_title("the main metric against its threshold, nominal and faulty windows")
    ax.grid(True, alpha=0.3)
    if margins:
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "margins.png", dpi=100)
    plt.close(fig)


def _threshold_lines(runs: list[CampaignRun]) -> list[str]:
    """What decided the main detector's nominal windows, summed over the runs'
    ``fdir_thresholds`` (summary.json; a test older summaries lack counts none): which
    threshold was in force, how often the hardware model's and Eq. 11-12's thresholds lay
    above the floor guard, which tests failed, and how the nominal ratios sat in the hardware
    model's distribution."""
    census = [r.summary.fdir_thresholds for r in runs if r.summary.fdir_thresholds]
    if not census:
        return []
    c = functools.reduce(operator.add, census)
    n = c.nominal_windows
    by = ", ".join(f"{k} {share(v, n)}" for k, v in c.threshold_by)
    above, sampled = c.model_above_floor, c.sampled_above_floor
    failed = ", ".join(f"{k} {v}" for k, v in c.failed)
    zn = c.model_z.windows
    z = ", ".join(f"|z| > {k}: {share(v, zn)}" for k, v in
                  ((2, c.model_z.over_2), (3, c.model_z.over_3), (4, c.model_z.over_4)))
    return ["", "## Thresholds (main detector, nominal windows)", "",
            f"{n} nominal windows decided.  Threshold in force: {by}.  The hardware model's "
            f"threshold above the floor guard in {share(above, n)}; Eq. 11-12's sampled "
            f"threshold in {share(sampled, n)}.  Tests failed: {failed}.  Nominal ratios in "
            f"the hardware model (z = (x − μ)/σ; a Gaussian has 4.6%, 0.27%, 0.006%): {z}."]
