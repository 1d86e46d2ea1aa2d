"""The neighbours' study (``study = "neighbours"`` in a campaign file; issue 29): every case of a
campaign flown with ground passes twice, by its ``[[variants]]`` ``central`` (the ground's FDIR
alone) and ``neighbours`` (the neighbours' FDIR aboard on), side by side.

Latency is counted from the onset to when the deciding party declared (``declared_latency_s``:
for the ground, once the window's data came down in a pass; for the neighbours, when the first
observer applying the agreement rule sent its declaration).  False alarms of the neighbours'
FDIR are counted per neighbour-window (a subject's FDI window at least one neighbour decided),
over the nominal runs and over every nominal window of every run, each with its one-sided 95%
upper bound.  Writes ``study.md``, ``study.json`` and ``study/latency.png`` beside the report.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from harness.campaign.rescore import CampaignRun, false_alarm_bound, load_runs
from harness.summary import FaultScore, RunSummary  # noqa: E402

CENTRAL, NEIGHBOURS = "central", "neighbours"


@dataclass(frozen=True)
class Case:
    """One case flown both ways: its group (less the variant) and index, the run of each."""

    group: str
    index: str
    central: RunSummary | None
    neighbours: RunSummary | None

    def fault(self) -> FaultScore | None:
        """The ground's score of the case's (first) fault, central."""
        s = self.central or self.neighbours
        return s.scores.per_fault[0] if s and s.scores and s.scores.per_fault else None


def cases(runs: Sequence[CampaignRun]) -> list[Case]:
    """The campaign's runs paired by group and index across the two variants."""
    by: dict[tuple[str, str], dict[str, RunSummary]] = {}
    for r in runs:
        base, _, index = r.id.rpartition("-")
        group, _, variant = base.rpartition("-")
        if variant in (CENTRAL, NEIGHBOURS):
            by.setdefault((group, index), {})[variant] = r.summary
    return [Case(g, i, v.get(CENTRAL), v.get(NEIGHBOURS)) for (g, i), v in sorted(by.items())]


def _ground_latency(s: RunSummary | None) -> float | None:
    f = s.scores.per_fault[0] if s and s.scores and s.scores.per_fault else None
    return f.declared_latency_s if f is not None and f.isolated else None


def _neighbour_latency(s: RunSummary | None) -> float | None:
    nb = s.neighbours if s else None
    f = nb.scores.per_fault[0] if nb and nb.scores.per_fault else None
    return f.declared_latency_s if f is not None and f.isolated else None


def _quantiles(values: Sequence[float | None]) -> str:
    got = [v for v in values if v is not None]
    if not got:
        return f"0/{len(values)}"
    q = np.percentile(got, [50, 90])
    return f"{len(got)}/{len(values)}: {q[0]:.0f} / {q[1]:.0f} / {max(got):.0f}"


def _false_alarms(summaries: Sequence[RunSummary]) -> tuple[int, int]:
    """False declarations of the neighbours and nominal neighbour-windows, summed."""
    nb = [s.neighbours for s in summaries if s.neighbours is not None]
    return (sum(n.scores.false_alarms for n in nb), sum(n.scores.nominal_cycles for n in nb))


def _rate(fa: int, windows: int) -> str:
    if windows == 0:
        return "no window"
    return (f"{fa} in {windows} ({fa / windows:.2e} per neighbour-window; 95% ≤ "
            f"{false_alarm_bound(fa, windows):.2e})")


def _group_rows(all_cases: list[Case]) -> list[str]:
    rows = ["| faults | cases | ground alone: declared (median / p90 / max, s) | neighbours: "
            "declared | ground, with the neighbours on | upheld / overruled |",
            "|---|---|---|---|---|---|"]
    groups = sorted({c.group for c in all_cases if c.fault() is not None})
    for g in [*groups, "all"]:
        mine = [c for c in all_cases if c.fault() is not None and g in (c.group, "all")]
        upheld = sum(c.neighbours.neighbours.disagreements.upheld for c in mine
                     if c.neighbours and c.neighbours.neighbours)
        over = sum(c.neighbours.neighbours.disagreements.overruled for c in mine
                   if c.neighbours and c.neighbours.neighbours)
        central = _quantiles([_ground_latency(c.central) for c in mine])
        rows.append(f"| {g} | {len(mine)} | {central} | "
                    f"{_quantiles([_neighbour_latency(c.neighbours) for c in mine])} | "
                    f"{_quantiles([_ground_latency(c.neighbours) for c in mine])} | "
                    f"{upheld} / {over} |")
    return rows


def _fmt(v: float | None) -> str:
    return "-" if v is None else f"{v:.0f}"


def _case_rows(all_cases: list[Case]) -> list[str]:
    rows = ["| case | fault | onset (s) | ground alone (s) | neighbours (s): judges | "
            "ground with them (s) | ruling |", "|---|---|---|---|---|---|---|"]
    for c in all_cases:
        f = c.fault()
        if f is None:
            continue
        nb = c.neighbours.neighbours if c.neighbours else None
        det = next((d for d in (c.neighbours.detections or []) if d.declared_by == "neighbours"
                    and d.spacecraft == f.spacecraft and (d.declared_s or 0) >= f.start_s),
                   None) if c.neighbours else None
        ruling = nb.rulings.get(f"{det.spacecraft}@{det.time_s:g}", "-") if nb and det else "-"
        rows.append(f"| {c.group}-{c.index} | sc{f.spacecraft} {f.kind} | {f.start_s:.0f} | "
                    f"{_fmt(_ground_latency(c.central))} | {_fmt(_neighbour_latency(c.neighbours))}"
                    f": {', '.join(map(str, det.judges or [])) if det else '-'} | "
                    f"{_fmt(_ground_latency(c.neighbours))} | {ruling} |")
    return rows


def _plot(path: Path, all_cases: list[Case]) -> None:
    faulty = [c for c in all_cases if c.fault() is not None]
    x = np.arange(len(faulty))
    fig, ax = plt.subplots(figsize=(max(6.0, 0.3 * len(faulty)), 4.0))
    for getter, run, label, marker in (
            (_ground_latency, "central", "ground alone", "s"),
            (_neighbour_latency, "neighbours", "neighbours aboard", "o")):
        y = [getter(getattr(c, run)) for c in faulty]
        ax.plot(x, [np.nan if v is None else v for v in y], marker, label=label)
    ax.axhline(60.0, color="k", lw=0.8, ls=":")
    ax.set_yscale("log")
    ax.set_xticks(x, [f"{c.group}-{c.index}" for c in faulty], rotation=90, fontsize=6)
    ax.set_ylabel("onset to declaration (s)")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_neighbours_study(out: Path, ids: Sequence[str]) -> Path:
    """Write ``<out>/study.md``, ``study.json`` and ``study/latency.png`` from the finished
    runs of a campaign with ``central`` and ``neighbours`` variants."""
    all_cases = cases(load_runs(out, ids))
    (out / "study").mkdir(exist_ok=True)
    _plot(out / "study" / "latency.png", all_cases)
    on = [c.neighbours for c in all_cases if c.neighbours is not None]
    nominal_on = [c.neighbours for c in all_cases if c.neighbours is not None
                  and c.fault() is None]
    dis = [s.neighbours.disagreements for s in on if s.neighbours is not None]
    judge = [s.neighbours.windows for s in on if s.neighbours is not None]
    pairs = sum(1 for c in all_cases if c.central and c.neighbours)
    lines = ["# Between ground passes: the ground alone, and with the neighbours' FDIR", "",
             f"{len(all_cases)} cases, {pairs} flown both ways. Latency: onset to the "
             "declaration of whoever decided (the ground: once the window's data came down in "
             "a pass). Neighbours' false alarms: per neighbour-window, with the one-sided "
             "95% upper bound.", "",
             "## Detection latency, by fault group", "", *_group_rows(all_cases), "",
             "![latency](study/latency.png)", "",
             "## False alarms of the neighbours' FDIR", "",
             f"- Over the nominal runs: {_rate(*_false_alarms(nominal_on))}.",
             f"- Over every nominal window of every run: {_rate(*_false_alarms(on))}.",
             f"- Judges' verdicts on a healthy neighbour that failed: "
             f"{sum(j.nominal_exceeded for j in judge)} of "
             f"{sum(j.nominal_judge_windows for j in judge)}.", "",
             "## The ground against the neighbours", "",
             f"Declarations upheld {sum(d.upheld for d in dis)}, overruled "
             f"{sum(d.overruled for d in dis)}, not ruled on by the run's end "
             f"{sum(d.unruled for d in dis)}; spacecraft the ground declared that the "
             f"neighbours had not: {sum(d.ground_only for d in dis)}.", "",
             "## Cases", "", *_case_rows(all_cases), ""]
    path = out / "study.md"
    path.write_text("\n".join(lines) + "\n")
    (out / "study.json").write_text(json.dumps([{
        "case": f"{c.group}-{c.index}", "central_latency_s": _ground_latency(c.central),
        "neighbours_latency_s": _neighbour_latency(c.neighbours),
        "ground_with_neighbours_latency_s": _ground_latency(c.neighbours)}
        for c in all_cases], indent=1) + "\n")
    return path
