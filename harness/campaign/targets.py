"""A campaign's figures against the detection targets (issue 39; docs/results.md), from
results.csv's rows of the main detector and the runs' neighbours sections:

* faults a window could judge (``rescore.fault_rows``: ``unjudged`` when none of its
  observer's windows after the onset reached the ground in the run) and those none could,
  apart, by where the onset fell (in contact, between passes);
* of the judgeable: detected and isolated (≥ 98%), identified per expected class (≥ 95%
  each); of those that began after their observer's first judgeable image
  (``judgeable_s`` ≤ onset), the latency from onset (median ≤ 10 s, p90 ≤ 30 s; issue 41)
  and each class's identification latency from onset (median ≤ 30 s); the latency from the
  first judgeable window, and from onset to when the ground declared it (with passes, after
  the data came down), without a target;
* false alarms per nominal observer-window (the ground) and per nominal neighbour-window (the
  neighbours aboard), 95% upper bound ≤ 1e-3; where the windows are too few for the bound to
  reach the target even at the false alarms seen (none: 2,995 windows at least), the figure
  says so and how many it needs (:func:`windows_needed`), not "not met";
* faults between passes in runs with the neighbours on: the first declaration, by the
  neighbours aboard or the ground, from onset (median ≤ 20 s).

Each figure is a :class:`Figure`: what it is, its value as text, the target as text, and
whether the target is met (None: nothing to judge it on, or too little: ``note`` says why).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from harness.campaign.rescore import (
    CampaignRun,
    false_alarm_bound,
    latency_summary,
    neighbour_false_alarms,
    spread,
    values,
)
from interfaces.contracts.timing import TIME_TOL_S

DETECTED_MIN = 0.98
IDENTIFIED_MIN = 0.95
ONSET_MEDIAN_S, ONSET_P90_S = 10.0, 30.0
IDENTIFIED_MEDIAN_S = 30.0
FALSE_ALARMS_MAX = 1e-3
OUT_OF_CONTACT_MEDIAN_S = 20.0


@dataclass(frozen=True)
class Figure:
    """One line of the table: a figure, its measured value, its target, met or not."""

    name: str
    value: str
    target: str = ""
    met: bool | None = None
    note: str = ""
    """why the target can be neither met nor missed (too few windows), shown for the mark"""


def share(n: int, d: int) -> str:
    """"x% (n/d)", or "-" without a denominator."""
    return "-" if d == 0 else f"{100.0 * n / d:.0f}% ({n}/{d})"


def rate(n: int, d: int) -> str:
    """False alarms per window with counts and the 95% upper bound, or "-"."""
    return "-" if d == 0 else f"{n / d:.4f} ({n}/{d}; 95% ≤ {false_alarm_bound(n, d):.2g})"


def noted_rate(n: int, d: int) -> str:
    """:func:`rate`, and where ``d`` windows are too few to show the target, how many would
    (:func:`too_few`)."""
    note = too_few(n, d)
    return rate(n, d) + (f"; {note}" if note else "")


def _quantiles_met(lat: Sequence[float], median_max: float, p90_max: float | None
                   ) -> bool | None:
    if not lat:
        return None
    return bool(np.median(lat) <= median_max
                and (p90_max is None or np.quantile(lat, 0.9) <= p90_max))


def windows_needed(false_alarms: int, target: float, confidence: float = 0.95) -> int:
    """The fewest windows in which ``false_alarms`` false alarms give a one-sided upper bound
    (``rescore.false_alarm_bound``, Clopper-Pearson) at or under ``target``, per window.  With
    none it is the closed form: 1 − (1 − confidence)^(1/n) ≤ target for
    n ≥ ln(1 − confidence) / ln(1 − target)."""
    lo, hi = max(false_alarms, 1), max(false_alarms, 1)
    while false_alarm_bound(false_alarms, hi, confidence) > target:  # the bound falls with n
        lo, hi = hi, 2 * hi
    while lo < hi:
        mid = (lo + hi) // 2
        if false_alarm_bound(false_alarms, mid, confidence) > target:
            lo = mid + 1
        else:
            hi = mid
    return hi


def too_few(false_alarms: int, windows: int, target: float = FALSE_ALARMS_MAX) -> str:
    """Where ``windows`` cannot show the target with the ``false_alarms`` seen (their rate is
    under it, their bound above), how many would: "" when they can, when the rate is over the
    target (not met), or without a window."""
    if windows == 0 or false_alarms > target * windows or \
            false_alarm_bound(false_alarms, windows) <= target:
        return ""
    at = f" with {false_alarms} false alarm{'s' if false_alarms > 1 else ''}" \
        if false_alarms else ""
    return (f"too few windows to show the target: needs ≥ "
            f"{windows_needed(false_alarms, target):,} windows{at} (has {windows:,})")


def _bound_figure(name: str, false_alarms: int, windows: int) -> Figure:
    """A false-alarm figure against ``FALSE_ALARMS_MAX``: met, not met, or too few windows to
    say (``note``)."""
    note = too_few(false_alarms, windows)
    met = None if windows == 0 or note else \
        false_alarm_bound(false_alarms, windows) <= FALSE_ALARMS_MAX
    return Figure(name, rate(false_alarms, windows), f"95% bound ≤ {FALSE_ALARMS_MAX:g}", met,
                  note)


def target_figures(rows: Sequence[dict[str, Any]], runs: Sequence[CampaignRun]
                   ) -> list[Figure]:
    """The figures (module docstring) of the main detector's results.csv ``rows`` and the
    ``runs`` they come from."""
    faults = [r for r in rows if r["detector"] == "main" and r["kind"] != "none"]
    judged = [r for r in faults if not r["unjudged"]]
    unjudged = [r for r in faults if r["unjudged"]]
    isolated = sum(r["isolated"] for r in judged)
    nominal = {r["run"]: r for r in rows if r["detector"] == "main"}.values()
    fa, windows = sum(r["false_alarms"] for r in nominal), sum(r["nominal_cycles"]
                                                                for r in nominal)
    nfa, nwin = neighbour_false_alarms(runs)
    after = [r for r in judged if r["judgeable_s"] <= r["start_s"] + TIME_TOL_S]
    with_neighbours = {r.id for r in runs if r.summary.neighbours is not None}
    between = [r for r in faults if r["contact"] == "between_passes"
               and r["run"] in with_neighbours]
    first = values(between, "first_latency_s")
    out = [Figure("faults (no window could judge)",
                  f"{len(faults)} ({len(unjudged)}: "
                  f"{sum(r['contact'] == 'between_passes' for r in unjudged)} between passes)"),
           Figure("detected and isolated, of the judgeable", share(isolated, len(judged)),
                  f"≥ {DETECTED_MIN:.0%}",
                  None if not judged else isolated >= DETECTED_MIN * len(judged))]
    out += _identified_figures(judged, after)
    onset = [r["latency_s"] for r in after if r["isolated"] and r["latency_s"] is not None]
    out += [Figure(f"latency from onset, the {len(after)} faults after their observer's first "
                   "judgeable image, median / p90 / max (s)", spread(onset),
                   f"≤ {ONSET_MEDIAN_S:g} / ≤ {ONSET_P90_S:g}",
                   _quantiles_met(onset, ONSET_MEDIAN_S, ONSET_P90_S)),
            Figure("latency from the first judgeable window (s)",
                   spread(values(judged, "window_latency_s"))),
            Figure("latency from onset, all judgeable (s)", latency_summary(judged)),
            Figure("latency from onset, when the ground declared it (s)",
                   spread(values(judged, "declared_latency_s"))),
            _bound_figure("false alarms per nominal observer-window (ground)", fa, windows),
            _bound_figure("false alarms per nominal neighbour-window (neighbours)", nfa, nwin),
            Figure(f"between passes, neighbours on ({len(between)} faults, {len(first)} "
                   "declared): first declaration from onset (s)", spread(first),
                   f"median ≤ {OUT_OF_CONTACT_MEDIAN_S:g}",
                   _quantiles_met(first, OUT_OF_CONTACT_MEDIAN_S, None))]
    return out


def _identified_figures(judged: Sequence[dict[str, Any]], after: Sequence[dict[str, Any]]
                        ) -> list[Figure]:
    """Identified, of the judgeable faults, per expected class; and the class's
    identification latency from onset, of those ``after`` their observer's first judgeable
    image."""
    out = []
    for cls in sorted({r["expected_class"] for r in judged if r["expected_class"]}):
        mine = [r for r in judged if r["expected_class"] == cls]
        right = sum(r.get("identified_class") == cls for r in mine)
        named = [r["identification_latency_s"] for r in after
                 if r["expected_class"] == cls and r.get("identified_class") == cls
                 and r.get("identification_latency_s") is not None]
        out += [Figure(f"identified as {cls}", share(right, len(mine)),
                       f"≥ {IDENTIFIED_MIN:.0%}", right >= IDENTIFIED_MIN * len(mine)),
                Figure(f"{cls} named, from onset ({len(named)} after the first judgeable "
                       "image), median / p90 / max (s)", spread(named),
                       f"median ≤ {IDENTIFIED_MEDIAN_S:g}",
                       _quantiles_met(named, IDENTIFIED_MEDIAN_S, None))]
    return out


def target_lines(figures: Sequence[Figure]) -> list[str]:
    """The report's section."""
    mark = {True: "met", False: "**not met**", None: "-"}
    lines = ["", "## Against the targets (main detector)", "",
             "A fault no window could judge (none of its observer's windows after the onset "
             "reached the ground in the run: between passes with no pass after it in the run; "
             "a link fault: no pass after it; a data-integrity fault where the crosslinks' "
             "loss kept the check from judging) is counted apart; the rates and the latency "
             "from the first judgeable window are over the others "
             "(harness/campaign/rescore.py, harness/campaign/targets.py).",
             "",
             "| figure | measured | target | |", "|---|---|---|---|"]
    return lines + [f"| {f.name} | {f.value} | {f.target} | "
                    f"{(f.note or mark[f.met]) if f.target else ''} |" for f in figures] + [""]
