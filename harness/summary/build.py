"""summary.json of a run (docs/contracts.md; its type: ``harness.summary``),
computed from the archive read back."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, TypeVar

from pydantic import BaseModel

from harness.summary.coverage_eval import coverage_summary
from harness.summary.digest import RunDigest, digest_run
from harness.summary.control_eval import gnc_summary
from harness.summary.ground_contact_eval import ground_contact
from harness.summary.neighbours_eval import neighbours_summary
from harness.summary.onboard_eval import onboard_summary
from harness.summary import (
    BUS_HEADER,
    AccessAudit,
    ArchiveInfo,
    Detection,
    ExecRecord,
    FailedTests,
    FaultEventRecord,
    FdirResults,
    FdirSeries,
    LostMessages,
    MainWindow,
    MessageCounts,
    ModelZ,
    NavStats,
    RecoveryComparison,
    RunFdirSettings,
    RunSummary,
    Scores,
    SegmentRecord,
    SeriesWindow,
    PaceRecord,
    SimRecord,
    ThresholdCensus,
    ThresholdSources,
)
from harness.summary.scoring import Alarm, Judged, overlaps_fault, score
from harness.archive.reader import ArchiveError, RunArchive
from ground.archive.segments import run_archive
from harness.archive.sequences import by_topic
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    WINDOW_TESTS,
    BaselineVerdict,
    ExecStats,
    FaultReport,
    FdirWindow,
    LinkStats,
    Message,
    SimStatus,
    Tick,
)
from interfaces.contracts.scenario import Scenario

M = TypeVar("M", bound=Message)
B = TypeVar("B", bound=BaseModel)

NAV_SETTLE_S = 10.0
"""Nav statistics skip the filter's first seconds (initial transient)."""


@dataclass(frozen=True)
class RunOutcome:
    """How a run went, from outside its archive: its transport, wall time (s), status and
    error (None if none)."""

    transport: Literal["inproc", "zenoh"]
    wall_s: float
    status: Literal["completed", "degraded", "failed"]
    error: str | None = None


def summary_head(scenario: Scenario, outcome: RunOutcome) -> RunSummary:
    """The fields every run's summary has, from its scenario and outcome."""
    return RunSummary(scenario=scenario.name, seed=scenario.seed, transport=outcome.transport,
                      duration_s=scenario.duration_s, wall_s=round(outcome.wall_s, 3),
                      status=outcome.status, error=outcome.error,
                      injected_faults=_copies(scenario.faults))


def build_summary(digest: RunDigest, scenario: Scenario, mission: str,
                  outcome: RunOutcome) -> RunSummary:
    """The run's summary: its head, then its figures from its archive."""
    archive = digest.archive
    tick_key = (cat.TICK.key(mission), Tick.__name__)
    last_tick = digest.counters.last.get(tick_key)
    execs = _last_of(digest, ExecStats)
    links = _last_of(digest, LinkStats)
    tlm = archive.of(cat.TLM_STATUS, mission)
    summary = summary_head(scenario, outcome)
    summary.archive = archive_info(archive)
    summary.ticks = digest.counters.counts.get(tick_key, 0)
    t_final = last_tick.decode(Tick).t_sim if last_tick is not None else 0.0
    summary.t_sim_final_s = t_final
    summary.messages = MessageCounts(total=len(archive), by_type=_by_type(archive))
    summary.nav = {str(sc): _nav_stats(e.stats(skip_s=NAV_SETTLE_S))
                   for sc, e in digest.nav_errors(mission).items()}
    summary.gnc = gnc_summary(digest.gnc_series(scenario, mission))
    summary.coverage = coverage_summary(digest.coverage)
    summary.links = _copies([c for node in sorted(links) for c in links[node].links],
                            exclude_none=True)
    contact = ground_contact(scenario, summary.links)
    if contact is not None:  # unset otherwise: not written
        summary.ground_contact = contact
    summary.exec = {node: _exec_record(m) for node, m in sorted(execs.items())}
    summary.telemetry = _copies(tlm[-1].entries) if tlm else []
    summary.sim = _sim_record(archive.of(cat.SIM_STATUS, mission))
    summary.fault_events = [FaultEventRecord.model_validate(e.model_dump(exclude=BUS_HEADER))
                            for e in archive.of(cat.FAULT_EVENTS, mission)]
    summary.set_fdir(fdir_summary(archive, scenario, mission))
    if scenario.onboard_fdir.enabled:
        summary.onboard_fdir = onboard_summary(archive, mission, scenario.faults, summary.scores)
    if scenario.neighbours.enabled:
        summary.neighbours, found = neighbours_summary(archive, scenario, mission,
                                                       summary.detections or [])
        summary.detections = [*(summary.detections or []), *found]
    summary.real_time_factor = round(t_final / outcome.wall_s, 2) if outcome.wall_s > 0 else None
    return summary


def archive_info(archive: RunArchive) -> ArchiveInfo:
    """``archive``: whether a file of it is truncated; its segments and the messages lost,
    only when it has several segments or lost messages (a clean run of one file says
    nothing more than it always did)."""
    info = ArchiveInfo(truncated=archive.truncated)
    if len(archive.segments) > 1 or archive.lost:
        lost = by_topic(archive.lost)
        info.segments = [SegmentRecord(file=s.path.name, truncated=s.truncated)
                         for s in archive.segments]
        info.lost = LostMessages(total=sum(lost.values()), by_topic=lost)
    return info


def _nav_stats(stats: dict[str, float]) -> NavStats | None:
    """An observer's nav statistics (None: no estimate after the settling time)."""
    return NavStats.model_validate(stats) if stats else None


def _exec_record(m: ExecStats) -> ExecRecord:
    return ExecRecord(cycle_slips={g: s.cycle_slips for g, s in m.groups.items()},
                      max_exec_ms={g: round(s.max_exec_ms, 3) for g, s in m.groups.items()},
                      app_errors=m.app_errors, invalid_dropped=m.invalid_dropped,
                      refused=m.refused, barrier_timeouts=m.barrier_timeouts)


def _sim_record(statuses: list[SimStatus]) -> SimRecord:
    """``sim`` from the sim's last status (none: nothing rejected is known)."""
    if not statuses:
        return SimRecord(rejected_commands=None, participants={})
    last = statuses[-1]
    record = SimRecord(rejected_commands=last.rejected_commands,
                       participants={n: _copies(ev) for n, ev in last.participants.items()})
    if last.pace_ceiling is not None:
        record.pace = PaceRecord(ceiling=last.pace_ceiling, hard_deadline=last.hard_deadline,
                                 late_ticks=dict(last.late_ticks))
    return record


def _copies(records: Sequence[B], exclude_none: bool = False) -> list[B]:
    """Copies of ``records`` with every field given (as written: a message decoded from the
    bus holds only the fields its sender gave, and a summary writes the fields given); with
    ``exclude_none``, those that are None are left unset (not written)."""
    return [type(r).model_validate(r.model_dump(exclude_none=exclude_none)) for r in records]


def fdir_summary(archive: RunArchive, scenario: Scenario, mission: str) -> FdirResults:
    """``detections`` (the ground FDIR's fault reports) and ``scores`` against the injected
    faults (harness/summary/scoring.py; grace of one FDI window)."""
    return fdir_results(archive.of(cat.FAULT_REPORT, mission),
                        archive.of(cat.FDIR_WINDOW, mission), archive.of(cat.BASELINE, mission),
                        scenario)


def fdir_results(reports: list[FaultReport], windows: list[FdirWindow],
                 verdicts: list[BaselineVerdict], scenario: Scenario) -> FdirResults:
    """The FDIR part of summary.json from the ground's own output messages (a live run's
    archive or a replay): detections, scores, baselines, series and settings."""
    alarms = [Alarm(r.spacecraft, r.t_sim, r.fault_class, r.declared_s) for r in reports
              if r.cause is None]  # a known cause (store overflow) is no alarm of a fault
    judged = [Judged(w.spacecraft, w.t_start_s, w.t_end_s) for w in windows
              if w.exceeded is not None]
    return FdirResults(
        detections=[Detection(spacecraft=r.spacecraft, time_s=r.t_sim, fault_class=r.fault_class,
                              direction=r.direction, metric=r.metric, threshold=r.threshold,
                              evidence=dict(r.evidence), declared_s=r.declared_s,
                              declared_by="ground",
                              **({"cause": r.cause} if r.cause else {}))
                    for r in reports],
        scores=score(scenario.faults, alarms, judged, grace_s=scenario.rates.fdi_period_s),
        baselines=baseline_scores(verdicts, scenario),
        fdir_series=_series(windows, verdicts),
        fdir_thresholds=threshold_census(windows, scenario),
        fdir_settings=RunFdirSettings.model_validate(
            {"fdi_period_s": scenario.rates.fdi_period_s, **scenario.fdir.model_dump()}))


def threshold_census(windows: list[FdirWindow], scenario: Scenario) -> ThresholdCensus:
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
    return ThresholdCensus(
        nominal_windows=len(nominal),
        threshold_by=ThresholdSources.model_validate(
            {k: sum(w.threshold_by == k for w in nominal) for k in ("model", "sampled", "floor")}),
        model_above_floor=sum((w.threshold_model or 0.0) > floor for w in nominal),
        sampled_above_floor=sum((w.threshold_sampled or 0.0) > floor for w in nominal),
        failed=FailedTests.model_validate({k: sum(k in w.failed for w in nominal)
                                            for k in WINDOW_TESTS}),
        model_z=ModelZ(over_2=sum(v > 2 for v in z), over_3=sum(v > 3 for v in z),
                       over_4=sum(v > 4 for v in z), windows=len(z)))


def _series(windows: list[FdirWindow], verdicts: list[BaselineVerdict]) -> FdirSeries:
    """``fdir_series``: every decided window of each detector (``run_summary.series``) --
    what a campaign needs to re-score at other threshold scales (ROC) without the archives.
    The main detector's windows record whether they failed a test other than the information
    test (plan, pointing, Δv rate, NIS: ``FdirWindow.failed``), which no threshold scale
    moves."""
    main = [MainWindow(spacecraft=w.spacecraft, t_start_s=w.t_start_s, t_end_s=w.t_end_s,
                       statistic=w.metric, threshold=w.threshold,
                       other_tests_failed=any(t != "information" for t in w.failed))
            for w in windows if w.metric is not None and w.threshold is not None]
    baselines: dict[str, list[SeriesWindow]] = {}
    for v in verdicts:
        if v.statistic is not None and v.threshold is not None:
            baselines.setdefault(v.detector, []).append(SeriesWindow(
                spacecraft=v.spacecraft, t_start_s=v.t_start_s, t_end_s=v.t_end_s,
                statistic=v.statistic, threshold=v.threshold))
    return FdirSeries(main=main, baselines=baselines)


def baseline_scores(verdicts: list[BaselineVerdict], scenario: Scenario) -> dict[str, Scores]:
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


def write_summary(out: Path, scenario: Scenario, transport: Literal["inproc", "zenoh"],
                  wall_s: float, status: Literal["completed", "degraded", "failed"],
                  error: str | None = None, mission: str | None = None,
                  digest: RunDigest | None = None,
                  access: AccessAudit | None = None) -> RunSummary:
    """Write ``<out>/summary.json`` and return it.  A damaged or missing archive is reported in
    the summary (``archive_error``), never hidden.  ``digest``: the run's archive already read
    (``harness.summary.digest``; the report then reuses it), else ``<out>/run.mcap`` (and the
    segments after it) is read.
    ``access``: the router's audit (from outside the archive)."""
    outcome = RunOutcome(transport, wall_s, status, error)
    try:
        digest = digest or digest_run(run_archive(out), scenario, mission or scenario.name)
        summary = build_summary(digest, scenario, mission or scenario.name, outcome)
    except (ArchiveError, OSError) as e:
        summary = summary_head(scenario, outcome)
        if digest is not None:  # read, then found damaged
            summary.archive = archive_info(digest.archive)
        summary.archive_error = str(e)
    if access is not None:
        summary.access = access
    summary.write(out / "summary.json")
    return summary


def add_recovery_comparison(out: Path, summary: RunSummary, counter: RunSummary,
                            recovery: bool) -> RunSummary:
    """Add ``recovery`` to ``<out>/summary.json``: the recovery actions of the run that had
    recovery on, and the final H with and without recovery for the same scenario and seed
    (``counter``: the summary of the same scenario with recovery flipped)."""
    with_r, without = (summary, counter) if recovery else (counter, summary)
    h_with = with_r.coverage.H_final if with_r.coverage else None
    h_without = without.coverage.H_final if without.coverage else None
    summary.recovery = RecoveryComparison(
        enabled=recovery,
        actions=[d for d in (with_r.coverage.assignment_decisions if with_r.coverage else [])
                 if d.reason == "recovery"],
        H_final_with_recovery=h_with,
        H_final_without_recovery=h_without,
        H_final_ratio=h_with / h_without if h_with is not None and h_without else None,
        counterfactual="counterfactual/summary.json",
        counterfactual_status=counter.status)
    summary.write(out / "summary.json")
    return summary
