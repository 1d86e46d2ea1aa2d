"""summary.json of a run (docs/contracts.md), computed from the archive read back."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, TypeVar

from ground.analysis.coverage import coverage_summary
from ground.analysis.digest import RunDigest, digest_run
from ground.analysis.gnc import gnc_summary
from ground.analysis.scoring import Alarm, Judged, overlaps_fault, score
from ground.archive.reader import ArchiveError, RunArchive
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    WINDOW_TESTS,
    BaselineVerdict,
    ExecStats,
    FaultReport,
    FdirWindow,
    LinkStats,
    Message,
    Tick,
)
from interfaces.contracts.scenario import Scenario

M = TypeVar("M", bound=Message)

NAV_SETTLE_S = 10.0
"""Nav statistics skip the filter's first seconds (initial transient)."""


def build_summary(digest: RunDigest, scenario: Scenario, mission: str) -> dict[str, Any]:
    """The run's figures from its archive (no transport or wall-clock information)."""
    archive = digest.archive
    tick_key = (cat.TICK.key(mission), Tick.__name__)
    last_tick = digest.counters.last.get(tick_key)
    execs = _last_of(digest, ExecStats)
    links = _last_of(digest, LinkStats)
    tlm = archive.of(cat.TLM_STATUS, mission)
    sim = archive.of(cat.SIM_STATUS, mission)
    return {
        "ticks": digest.counters.counts.get(tick_key, 0),
        "t_sim_final_s": last_tick.decode(Tick).t_sim if last_tick is not None else 0.0,
        "messages": {"total": len(archive), "by_type": _by_type(archive)},
        "nav": {str(sc): e.stats(skip_s=NAV_SETTLE_S)
                for sc, e in digest.nav_errors(mission).items()},
        "gnc": gnc_summary(digest.gnc_series(scenario, mission)),
        "coverage": coverage_summary(digest.coverage),
        "links": [c.model_dump() for node in sorted(links) for c in links[node].links],
        "exec": {node: {"cycle_slips": {g: s.cycle_slips for g, s in m.groups.items()},
                        "max_exec_ms": {g: round(s.max_exec_ms, 3) for g, s in m.groups.items()},
                        "app_errors": m.app_errors, "invalid_dropped": m.invalid_dropped,
                        "refused": m.refused, "barrier_timeouts": m.barrier_timeouts}
                 for node, m in sorted(execs.items())},
        "telemetry": [e.model_dump() for e in tlm[-1].entries] if tlm else [],
        "sim": {"rejected_commands": sim[-1].rejected_commands if sim else None,
                "participants": ({n: [e.model_dump() for e in ev]
                                  for n, ev in sim[-1].participants.items()} if sim else {})},
        "fault_events": [e.model_dump(exclude={"sender", "seq", "t_wall"})
                         for e in archive.of(cat.FAULT_EVENTS, mission)],
        **fdir_summary(archive, scenario, mission),
    }


def fdir_summary(archive: RunArchive, scenario: Scenario, mission: str) -> dict[str, Any]:
    """``detections`` (the ground FDIR's fault reports) and ``scores`` against the injected
    faults (ground/analysis/scoring.py; grace of one FDI window)."""
    return fdir_results(archive.of(cat.FAULT_REPORT, mission),
                        archive.of(cat.FDIR_WINDOW, mission), archive.of(cat.BASELINE, mission),
                        scenario)


def fdir_results(reports: list[FaultReport], windows: list[FdirWindow],
                 verdicts: list[BaselineVerdict], scenario: Scenario) -> dict[str, Any]:
    """The FDIR part of summary.json from the ground's own output messages (a live run's
    archive or a replay): detections, scores, baselines, series and settings."""
    alarms = [Alarm(r.spacecraft, r.t_sim, r.fault_class) for r in reports]
    judged = [Judged(w.spacecraft, w.t_start_s, w.t_end_s) for w in windows
              if w.exceeded is not None]
    return {
        "detections": [{"spacecraft": r.spacecraft, "time_s": r.t_sim, "class": r.fault_class,
                        "direction": r.direction, "metric": r.metric, "threshold": r.threshold,
                        "evidence": r.evidence}
                       for r in reports],
        "scores": score(scenario.faults, alarms, judged, grace_s=scenario.rates.fdi_period_s),
        "baselines": baseline_scores(verdicts, scenario),
        "fdir_series": _series(windows, verdicts),
        "fdir_thresholds": threshold_census(windows, scenario),
        "fdir_settings": {"fdi_period_s": scenario.rates.fdi_period_s,
                          **scenario.fdir.model_dump()},
    }


def threshold_census(windows: list[FdirWindow], scenario: Scenario) -> dict[str, Any]:
    """``fdir_thresholds``: over the nominal windows the main detector decided (no fault of
    their spacecraft overlapping), what set the threshold in force (the hardware model, Eq.
    11-12's sampling, or the floor guard), how often each threshold lay above the floor, and
    which tests failed; with the nominal standardised ratios (x − μ)/σ of the hardware model
    beyond 2, 3 and 4."""
    floor = scenario.fdir.floor
    nominal = [w for w in windows if w.exceeded is not None
               and not overlaps_fault(scenario.faults, w.spacecraft, w.t_start_s, w.t_end_s)]
    z = [abs((w.dh / w.dh_pred - w.ratio_mean) / w.ratio_std) for w in nominal
         if w.dh is not None and w.dh_pred and w.ratio_mean is not None and w.ratio_std]
    return {
        "nominal_windows": len(nominal),
        "threshold_by": {k: sum(w.threshold_by == k for w in nominal)
                         for k in ("model", "sampled", "floor")},
        "model_above_floor": sum((w.threshold_model or 0.0) > floor for w in nominal),
        "sampled_above_floor": sum((w.threshold_sampled or 0.0) > floor for w in nominal),
        "failed": {k: sum(k in w.failed for w in nominal)
                   for k in WINDOW_TESTS},
        "model_z": {f"over_{k}": sum(v > k for v in z) for k in (2, 3, 4)} | {"windows": len(z)},
    }


def _series(windows: list[FdirWindow], verdicts: list[BaselineVerdict]
            ) -> dict[str, list[list[float]]]:
    """``fdir_series``: every decided window of each detector as [spacecraft, t_start_s,
    t_end_s, statistic, threshold] -- what a campaign needs to re-score at other threshold
    scales (ROC) without the archives.  The main detector's rows carry a sixth value, 1 when
    the window failed a test other than the information test (plan, pointing, Δv rate, NIS:
    ``FdirWindow.failed``), which no threshold scale moves."""
    out: dict[str, list[list[float]]] = {"main": [
        [w.spacecraft, w.t_start_s, w.t_end_s, w.metric, w.threshold,
         float(any(t != "information" for t in w.failed))] for w in windows
        if w.metric is not None and w.threshold is not None]}
    for v in verdicts:
        if v.statistic is not None and v.threshold is not None:
            out.setdefault(v.detector, []).append(
                [v.spacecraft, v.t_start_s, v.t_end_s, v.statistic, v.threshold])
    return out


def baseline_scores(verdicts: list[BaselineVerdict], scenario: Scenario
                    ) -> dict[str, dict[str, Any]]:
    """``baselines``: each baseline detector (ground/apps/baselines.py) scored like the main
    one, from its per-window verdicts."""
    out = {}
    for name in sorted({v.detector for v in verdicts}):
        mine = [v for v in verdicts if v.detector == name]
        alarms = [Alarm(v.spacecraft, v.t_end_s, None) for v in mine if v.alarm]
        judged = [Judged(v.spacecraft, v.t_start_s, v.t_end_s) for v in mine
                  if v.exceeded is not None]
        out[name] = score(scenario.faults, alarms, judged, grace_s=scenario.rates.fdi_period_s)
    return out


def _by_type(archive: RunArchive) -> dict[str, int]:
    out: dict[str, int] = {}
    for type_name, count in archive.topics().values():
        out[type_name] = out.get(type_name, 0) + count
    return dict(sorted(out.items()))


def _last_of(digest: RunDigest, model: type[M]) -> dict[str, M]:
    """The last ``model`` message of each key, by node (cumulative counters)."""
    msgs = [rec.decode(model) for (_, type_name), rec in digest.counters.last.items()
            if type_name == model.__name__]
    return {m.node: m for m in msgs}  # type: ignore[attr-defined]


def write_summary(out: Path, scenario: Scenario, transport: str, wall_s: float, status: str,
                  error: str | None = None, mission: str | None = None,
                  digest: RunDigest | None = None,
                  extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """Write ``<out>/summary.json`` and return it.  A damaged or missing archive is reported in
    the summary (``archive_error``), never hidden.  ``digest``: the run's archive already read
    (``ground.analysis.digest``; the report then reuses it), else ``<out>/run.mcap`` is read.
    ``extra``: sections from outside the archive (the router's ``access`` audit)."""
    summary: dict[str, Any] = {
        "scenario": scenario.name,
        "seed": scenario.seed,
        "transport": transport,
        "duration_s": scenario.duration_s,
        "wall_s": round(wall_s, 3),
        "status": status,
        "error": error,
        "injected_faults": [f.model_dump() for f in scenario.faults],
    }
    try:
        mission = mission or scenario.name
        digest = digest or digest_run(out / "run.mcap", scenario, mission)
        summary["archive"] = {"truncated": digest.archive.truncated}
        summary.update(build_summary(digest, scenario, mission))
        t_final = summary["t_sim_final_s"]
        summary["real_time_factor"] = round(t_final / wall_s, 2) if wall_s > 0 else None
    except (ArchiveError, OSError) as e:
        summary["archive_error"] = str(e)
    summary.update(extra or {})
    return _write_json(out, summary)


def add_recovery_comparison(out: Path, summary: dict[str, Any], counter: dict[str, Any],
                            recovery: bool) -> dict[str, Any]:
    """Add ``recovery`` to ``<out>/summary.json``: the recovery actions of the run that had
    recovery on, and the final H with and without recovery for the same scenario and seed
    (``counter``: the summary of the same scenario with recovery flipped)."""
    with_r, without = (summary, counter) if recovery else (counter, summary)

    def final_h(s: dict[str, Any]) -> float | None:
        return s.get("coverage", {}).get("H_final")

    h_with, h_without = final_h(with_r), final_h(without)
    summary["recovery"] = {
        "enabled": recovery,
        "actions": [d for d in with_r.get("coverage", {}).get("assignment_decisions", [])
                    if d.get("reason") == "recovery"],
        "H_final_with_recovery": h_with,
        "H_final_without_recovery": h_without,
        "H_final_ratio": h_with / h_without if h_with is not None and h_without else None,
        "counterfactual": "counterfactual/summary.json",
        "counterfactual_status": counter.get("status"),
    }
    return _write_json(out, summary)


def _write_json(out: Path, summary: dict[str, Any]) -> dict[str, Any]:
    summary = _finite(summary)
    (out / "summary.json").write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n")
    return summary


def _finite(o: Any) -> Any:
    """JSON has no NaN/inf: non-finite floats become null."""
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    if isinstance(o, dict):
        return {k: _finite(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_finite(v) for v in o]
    return o
