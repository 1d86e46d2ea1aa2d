"""A campaign's figures, before any rendering: its runs read back, each fault's row (detected,
isolated, identified, latencies from onset and from the first judgeable window), a detector's
statistics over the runs (rates, latencies, false alarms per nominal window with their 95%
bound), and the re-scoring of the archived windows under other rules (the threshold scaled,
m-of-n persistence: the ROC and the persistence table), without re-simulating.  The report
(``harness/campaign/report.py``) renders them; the campaign replay and the studies read them."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import beta

from ground.fdir.threshold import Persistence
from harness.summary import (
    OTHER_TESTS_FLAG,
    Detection,
    FaultScore,
    RunSummary,
    Scores,
    SeriesWindow,
)
from harness.summary.scoring import Alarm, Judged, score
from interfaces.contracts.scenario import Fault

SCALES = np.geomspace(0.1, 10.0, 41)
"""Threshold scales of the ROC sweep."""


@dataclass(frozen=True)
class CampaignRun:
    """A finished run of the campaign: its id, campaign group, the software version that ran
    it, its summary, and what it drew of its set-up (``drawn.json``: dimension → value, and
    each dimension's domain; ``deploy/draws.py``)."""

    id: str
    group: str
    version: str
    summary: RunSummary
    drawn: dict[str, Any] = field(default_factory=dict)
    domains: dict[str, dict[str, Any]] = field(default_factory=dict)


def _json_beside(summary: Path, name: str) -> dict[str, Any]:
    """A JSON file of the run's directory, or {} when it has none."""
    path = summary.parent / name
    return json.loads(path.read_text()) if path.exists() else {}


def load_runs(out: Path, ids: Sequence[str]) -> list[CampaignRun]:
    """The finished runs.  The group is the run's campaign group (one per paper figure in
    paper.toml); without a campaign.json, the id less its ``-<index>``.  Raises SummaryError
    for a summary that is not one."""
    runs = []
    for rid in ids:
        p = out / "runs" / rid / "summary.json"
        if p.exists():
            meta, drawn = _json_beside(p, "campaign.json"), _json_beside(p, "drawn.json")
            runs.append(CampaignRun(rid, meta.get("group") or rid.rsplit("-", 1)[0],
                                    meta.get("software_version", "unknown"),
                                    RunSummary.read(p), drawn.get("drawn", {}),
                                    drawn.get("domains", {})))
    return runs


def fault_rows(runs: list[CampaignRun]) -> list[dict[str, Any]]:
    """results.csv rows: per run, detector and fault (or one nominal row per detector).

    Besides the scores of ``harness/summary/scoring.py``, each fault row says when a window of
    the main detector could first judge it (``judgeable_s``; None: none could, ``unjudged``),
    its latency from that window's start (``window_latency_s``), when the ground declared it
    (``declared_latency_s``, from onset: with passes, once the data came down), where the
    onset fell (``contact``: continuous, in_pass, between_passes), when the neighbours aboard
    declared it (``neighbours_latency_s``, from onset) and the first of the two
    (``first_latency_s``); where the sequential test ran, which test declared it
    (``declaring_test``) and its delay bound (``image_divergence``, ``nis_divergence``,
    ``delay_bound_s``;
    ``harness/summary/delay_bound.py``)."""
    rows = []
    for run in runs:
        s = run.summary
        windows = _judged_windows(s)
        detectors = {"main": _main_scores(s), **(s.baselines or {})}
        neighbours = s.neighbours.scores.per_fault if s.neighbours is not None else []
        for name, sc in detectors.items():
            common = {"run": run.id, "group": run.group, "seed": s.seed, "status": s.status,
                      "detector": name, "false_alarms": sc.false_alarms if sc else 0,
                      "nominal_cycles": sc.nominal_cycles if sc else 0}
            faults = sc.per_fault if sc else []
            if not faults:
                rows.append({**common, "kind": "none"})
            main = name == "main"
            for i, f in enumerate(faults):
                rows.append({**common, "fault_index": i, "kind": f.kind,
                             "spacecraft": f.spacecraft, "start_s": f.start_s,
                             "magnitude": s.injected_faults[i].magnitude,
                             "detected": f.detected, "isolated": f.isolated,
                             "latency_s": f.latency_s,
                             "identified_class": f.identified_class if main else None,
                             "identification_latency_s": f.identification_latency_s
                             if main else None,
                             "expected_class": f.expected_class,
                             "declaring_test": f.detector if main else None,
                             "image_divergence": f.image_divergence if main else None,
                             "nis_divergence": f.nis_divergence if main else None,
                             "delay_bound_s": f.delay_bound_s if main else None,
                             **_timing(f, s.injected_faults[i].end_s, windows, run,
                                       neighbours[i] if i < len(neighbours) else None)})
    return rows


def _judged_windows(summary: RunSummary) -> dict[int, list[tuple[float, float]]]:
    """Each observer's windows the main detector judged, (start, end) s (its
    ``fdir_series``)."""
    out: dict[int, list[tuple[float, float]]] = {}
    for w in summary.fdir_series.main if summary.fdir_series else []:
        out.setdefault(w.spacecraft, []).append((w.t_start_s, w.t_end_s))
    return out


def _judgeable_s(fault: FaultScore, end_s: float | None,
                 windows: dict[int, list[tuple[float, float]]], summary: RunSummary,
                 integrity_blind: bool) -> float | None:
    """When a fault could first be judged, s (None: never in the run).

    * A link fault: once the ground hears the constellation after the onset (at once, or at
      the next pass's acquisition: a link is judged on what arrives, not in windows: a
      silence an FDI period after it, a dump's loss as it comes down), if the run lasts until
      that contact's end and a window more (the pass's dump judged).
    * A data-integrity fault in a run whose integrity check never judged (``integrity_blind``:
      the crosslinks lose more than ``fdir.integrity_max_loss``): never.
    * Any other: the start of the first judged window of its observer (of any observer for a
      common-mode fault, spacecraft 0) that ends after the onset and begins while the fault is
      on (before ``end_s`` and a window), or the onset when that window began earlier; with
      none (between passes: none came down in the run), the onset for a fault isolated all the
      same, else None."""
    if fault.expected_class == "link":
        return _heard_from_s(summary, fault.start_s)
    if fault.expected_class == "data_integrity" and integrity_blind:
        return None
    spans = [w for ws in windows.values() for w in ws] if fault.spacecraft == 0 \
        else windows.get(fault.spacecraft, [])
    until = math.inf if end_s is None else end_s + summary.fdir_settings.fdi_period_s
    t0 = min((a for a, b in spans if b > fault.start_s and a < until), default=None)
    if t0 is None:
        return fault.start_s if fault.isolated else None
    return max(fault.start_s, t0)


def _heard_from_s(summary: RunSummary, t_s: float) -> float | None:
    """The first time at or after ``t_s`` the ground hears the constellation, s: ``t_s`` with
    continuous contact or in a pass, else the next pass's acquisition; None when the run ends
    before that contact does, plus a window."""
    gc = summary.ground_contact
    if gc is None:
        return t_s
    end = (summary.duration_s or math.inf) - summary.fdir_settings.fdi_period_s
    return min((max(p.aos_s, t_s) for p in gc.passes if p.los_s > t_s and p.los_s <= end),
               default=None)


def _contact(summary: RunSummary, t_s: float) -> str:
    """Where ``t_s`` fell: ``continuous`` (the ground hears continuously), ``in_pass`` or
    ``between_passes``."""
    gc = summary.ground_contact
    if gc is None:
        return "continuous"
    return "in_pass" if any(p.aos_s <= t_s < p.los_s for p in gc.passes) else "between_passes"


def integrity_blind(run: CampaignRun) -> bool:
    """Whether the run's data-integrity check could judge nothing: the crosslinks' nominal
    loss above ``fdir.integrity_max_loss`` (``crosslink_loss`` among its unjudged reports; in
    summaries before that reason, the drawn ``comms.packet_loss``)."""
    census = run.summary.fdir_thresholds
    if census is not None and census.integrity_unjudged.crosslink_loss > 0:
        return True
    loss = run.drawn.get("comms.packet_loss")
    return isinstance(loss, int | float) and loss > run.summary.fdir_settings.integrity_max_loss


def _timing(fault: FaultScore, end_s: float | None, windows: dict[int, list[tuple[float, float]]],
            run: CampaignRun, neighbours: FaultScore | None) -> dict[str, Any]:
    """A fault row's judgeability and latencies (:func:`fault_rows`).  From the first
    judgeable window: to the declaring window's end, or for a link fault (whose window may
    end before the contact that brings it) to its declaration."""
    summary = run.summary
    judgeable = _judgeable_s(fault, end_s, windows, summary, integrity_blind(run))
    isolated = fault.isolated and fault.latency_s is not None
    declared = fault.declared_latency_s if isolated else None
    aboard = neighbours.declared_latency_s if neighbours is not None and neighbours.isolated \
        else None
    firsts = [t for t in (declared, aboard) if t is not None]
    since = fault.latency_s if fault.expected_class != "link" else declared
    window = None if not isolated or judgeable is None or since is None \
        else max(since - (judgeable - fault.start_s), 0.0)
    return {"judgeable_s": judgeable, "unjudged": judgeable is None,
            "contact": _contact(summary, fault.start_s), "window_latency_s": window,
            "declared_latency_s": declared, "neighbours_latency_s": aboard,
            "first_latency_s": min(firsts) if firsts else None}


def values(rows: Sequence[dict[str, Any]], key: str) -> list[float]:
    """The values of ``key`` in results.csv ``rows`` that have one."""
    return [r[key] for r in rows if r.get(key) is not None]


def latency_summary(faults: Sequence[dict[str, Any]], key: str = "latency_s") -> str:
    """"median / p90 / max" of the latency of the isolated faults (or ``key``), s, of
    results.csv rows."""
    return spread([f[key] for f in faults if f["isolated"] and f.get(key) is not None])


def spread(lat: Sequence[float]) -> str:
    """"median / p90 / max" of latencies, s."""
    if not lat:
        return "- / - / -"
    return f"{np.median(lat):.0f} / {np.quantile(lat, 0.9):.0f} / {max(lat):.0f}"


def isolated_latencies(rows: Sequence[dict[str, Any]]) -> list[float]:
    """Onset-to-declaration latencies (s) of the isolated faults among results.csv ``rows``."""
    return [r["latency_s"] for r in rows if r["kind"] != "none" and r["isolated"]
            and r["latency_s"] is not None]


def detector_stats(rows: Sequence[dict[str, Any]], hours: float) -> dict[str, Any]:
    """A detector's counts over results.csv ``rows``: faults, detected, isolated, identified,
    latencies (median / p90 / max), false alarms over nominal cycles (and per hour); and the
    same over the faults a window could judge (``isolated_judgeable``,
    ``identified_judgeable``), with the ``unjudged`` apart."""
    faults = [r for r in rows if r["kind"] != "none"]
    judgeable = [r for r in faults if not r.get("unjudged")]
    fa = sum(r["false_alarms"] for r in {(r["run"]): r for r in rows}.values())
    cycles = sum(r["nominal_cycles"] for r in {(r["run"]): r for r in rows}.values())
    return {
        "faults": len(faults),
        "detected": sum(r["detected"] for r in faults),
        "isolated": sum(r["isolated"] for r in faults),
        "identified": sum(r.get("identified_class") == r["expected_class"] for r in faults),
        "latency": latency_summary(faults),
        "identification_latency": latency_summary(
            [f for f in faults if f.get("identified_class") == f["expected_class"]],
            "identification_latency_s"),
        "unjudged": len(faults) - len(judgeable),
        "isolated_judgeable": sum(r["isolated"] for r in judgeable),
        "identified_judgeable": sum(r.get("identified_class") == r["expected_class"]
                                    for r in judgeable),
        "false_alarms": fa, "nominal_cycles": cycles,
        "false_alarms_per_hour": fa / hours if hours > 0 else None,
    }


def neighbour_false_alarms(runs: Sequence[CampaignRun]) -> tuple[int, int]:
    """The neighbours' false alarms and nominal neighbour-windows over the runs that had them
    on."""
    nb = [r.summary.neighbours.scores for r in runs if r.summary.neighbours is not None]
    return sum(s.false_alarms for s in nb), sum(s.nominal_cycles for s in nb)


def detector_figures(out: Path, ids: Sequence[str], detector: str = "main") -> dict[str, Any]:
    """One detector's figures over the finished runs ``ids`` of ``out`` (a campaign or its
    replay): faults, detected, isolated, identified (counts), latency median and p90 of the
    isolated faults (s), false alarms and nominal cycles (over whole runs, and over each
    replay's faithful span: ``harness.replay``), runs, and runs whose replay (if any)
    stayed faithful to the end."""
    runs = load_runs(out, ids)
    rows = [r for r in fault_rows(runs) if r["detector"] == detector]
    st = detector_stats(rows, 0.0)
    lat = isolated_latencies(rows)
    faithful = sum(_faithful_to_the_end(r.summary) for r in runs)
    spans = [_detector_scores(_main_scores(r.summary), r.summary, detector) for r in runs]
    whole = [_detector_scores(r.summary.scores, r.summary, detector) for r in runs]
    return {"faults": st["faults"], "detected": st["detected"], "isolated": st["isolated"],
            "identified": st["identified"],
            "latency_median_s": float(np.median(lat)) if lat else None,
            "latency_p90_s": float(np.quantile(lat, 0.9)) if lat else None,
            "false_alarms": sum(sc.false_alarms for sc in whole if sc),
            "nominal_cycles": sum(sc.nominal_cycles for sc in whole if sc),
            "false_alarms_faithful": sum(sc.false_alarms for sc in spans if sc),
            "nominal_cycles_faithful": sum(sc.nominal_cycles for sc in spans if sc),
            "runs": len(runs), "faithful_runs": int(faithful)}


def _faithful_to_the_end(summary: RunSummary) -> bool:
    """Whether the run is no replay, or a replay faithful to the run's end."""
    if summary.replay is None:
        return True
    return summary.duration_s is not None and \
        summary.replay.faithful_until_s >= summary.duration_s


def _main_scores(summary: RunSummary) -> Scores | None:
    """The main detector's scores of a run: over the faithful span for a replay (what the
    replay declared after its uplinks diverged from the flown run judges a trajectory nobody
    commanded; ``harness.replay``), else the run's own."""
    return summary.replay.scores_faithful if summary.replay else summary.scores


def _detector_scores(main: Scores | None, summary: RunSummary, detector: str
                     ) -> Scores | None:
    """The scores of ``detector`` in a summary: ``main`` for the main detector (the faithful
    span's, for a replay), else the baseline's."""
    return main if detector == "main" else (summary.baselines or {}).get(detector)


def false_alarm_bound(false_alarms: int, cycles: int, confidence: float = 0.95) -> float:
    """One-sided upper confidence bound of a per-cycle false-alarm probability from
    ``false_alarms`` in ``cycles`` (Clopper-Pearson: the beta quantile; 3/n for none)."""
    if false_alarms >= cycles:
        return 1.0
    return float(beta.ppf(confidence, false_alarms + 1, cycles - false_alarms))


def _fault_in(window: SeriesWindow, faults: list[Fault]) -> str | None:
    """The kind of an injected fault active on the window's spacecraft during the window, or
    None (a nominal window)."""
    for f in faults:  # spacecraft 0: a common-mode fault, on every observer
        if f.spacecraft in (0, window.spacecraft) and f.start_s < window.t_end_s \
                and (f.end_s is None or window.t_start_s < f.end_s):
            return str(f.kind)
    return None


def _series(summary: RunSummary, detector: str) -> Sequence[SeriesWindow]:
    """The windows ``detector`` decided in a run (none if unrecorded)."""
    return summary.fdir_series.of(detector) if summary.fdir_series else []


def nominal_hours(runs: list[CampaignRun], detector: str) -> float:
    """Spacecraft-hours a detector judged without a fault, from its windows."""
    total = 0.0
    for r in runs:
        for w in _series(r.summary, detector):
            if _fault_in(w, r.summary.injected_faults) is None:
                total += w.t_end_s - w.t_start_s
    return total / 3600.0


def window_margins(runs: list[CampaignRun]) -> dict[str, np.ndarray]:
    """The main detector's H_m,i / τ_i of every window, by the kind of the fault active in it
    (``"nominal"`` for none): the margin the threshold leaves on each side."""
    out: dict[str, list[float]] = {}
    for r in runs:
        for w in _series(r.summary, "main"):
            if w.threshold > 0.0:
                kind = _fault_in(w, r.summary.injected_faults) or "nominal"
                out.setdefault(kind, []).append(w.statistic / w.threshold)
    return {k: np.array(out[k]) for k in sorted(out, key=lambda k: (k != "nominal", k))}


def persistence_of(summary: RunSummary, detector: str) -> tuple[int, int]:
    """The persistence rule (m exceedances among the last n windows) the detector used in
    that run, from its settings as summary.json records them: the main detector and the
    window test beside the sequential one (``window``) m of ``persistence_window`` (or in a
    row), chi2_nis ``persistence`` in a row, the plain limit checks one.  A summary without
    settings: 2 in a row."""
    cfg = summary.fdir_settings
    m = cfg.persistence if cfg else 2
    if detector in ("main", "window"):
        return m, (cfg.persistence_window if cfg else None) or m
    return (m, m) if detector == "chi2_nis" else (1, 1)


def alarms_at(series: Sequence[SeriesWindow], scale: float, m: int, n: int) -> list[Alarm]:
    """The alarms a detector raises on its windows with its threshold scaled, under the
    detector's own rule (``threshold.Persistence``: ``m`` exceedances among the last ``n``
    windows, once per episode).  A main-detector window that failed one of its other tests
    counts as exceeded at every scale (``MainWindow.exceeded``)."""
    rule = Persistence(m, n)
    return [Alarm(w.spacecraft, w.t_end_s, None)
            for w in sorted(series, key=lambda w: (w.spacecraft, w.t_end_s))
            if rule.update(w.spacecraft, w.exceeded(scale))]


def information_only(runs: list[CampaignRun]) -> int:
    """How many runs' main-detector series predate the other-tests flag (filled in on load:
    ``OTHER_TESTS_FLAG``): their re-scoring sees the information test alone."""
    return sum(1 for r in runs if OTHER_TESTS_FLAG in r.summary.filled)


@dataclass
class Rescored:
    """A detector's figures over the runs when re-scored from its archived windows."""

    false_alarms: int = 0
    nominal_cycles: int = 0
    per_fault: list[FaultScore] = field(default_factory=list)


def rescore(runs: list[CampaignRun], detector: str, scale: float,
             rule: tuple[int, int] | None = None) -> Rescored:
    """Re-score each run's windows of ``detector`` with its threshold times ``scale`` and the
    persistence ``rule`` (m of the last n windows; None: the run's own, n in a row) exactly as
    summary.json is scored (``scoring.score``); the main detector's link and data-integrity
    declarations, which no threshold scales, are kept as they were, and the global check's
    (``common_mode``, Eq. 6) where its statistic passes its threshold times ``scale`` (its
    windows are not in ``fdir_series``: one it did not declare cannot be added)."""
    total = Rescored()
    for run in runs:
        s = run.summary
        if s.fdir_series is None or detector not in s.fdir_series.detectors():
            continue
        series = s.fdir_series.of(detector)
        grace = s.fdir_settings.fdi_period_s if s.fdir_settings else 0.0
        fixed = [Alarm(d.spacecraft, d.time_s, d.fault_class) for d in s.detections or []
                 if detector == "main" and d.declared_by == "ground" and _kept(d, scale)]
        judged = [Judged(w.spacecraft, w.t_start_s, w.t_end_s) for w in series]
        m, n = rule or persistence_of(s, detector)
        sc = score(s.injected_faults, fixed + alarms_at(series, scale, m, n), judged, grace)
        total.false_alarms += sc.false_alarms
        total.nominal_cycles += sc.nominal_cycles
        total.per_fault += sc.per_fault
    return total


def _kept(declared: Detection, scale: float) -> bool:
    """Whether a main-detector declaration that is not an observer window's stands in a
    re-scoring at ``scale`` (``rescore``)."""
    if declared.fault_class in ("link", "data_integrity"):
        return True
    return (declared.fault_class == "common_mode" and declared.metric is not None
            and declared.threshold is not None
            and declared.metric > scale * declared.threshold)


def roc(runs: list[CampaignRun], detector: str) -> tuple[np.ndarray, np.ndarray]:
    """(false alarms per nominal cycle, detection rate) at each threshold scale in SCALES,
    each run re-scored with its own persistence (``rescore``)."""
    fa, det = np.zeros(len(SCALES)), np.zeros(len(SCALES))
    for k, scale in enumerate(SCALES):
        r = rescore(runs, detector, scale)
        fa[k] = r.false_alarms / max(r.nominal_cycles, 1)
        det[k] = sum(f.detected for f in r.per_fault) / max(len(r.per_fault), 1)
    return fa, det


PERSISTENCE_RULES = ((1, 1), (2, 2), (2, 3), (3, 3))
"""Persistence rules (m exceedances in the last n windows) the report re-scores the main
detector with."""
