"""summary.json's FDIR sections: the ground's declarations (``detections``), their scores
against the injected faults (``scores``, ``baselines``), the decided windows
(``fdir_series``), what set the thresholds (``fdir_thresholds``) and the detector's settings
(``fdir_settings``); and a replay's results (``harness.replay``), which a campaign replay
writes into the run's summary.  The records, and the sections computed from the ground's
reports, windows and baselines' verdicts in a run's archive (scored by
``harness.summary.scoring``)."""

from __future__ import annotations

from typing import Any, ClassVar, Literal, Self

from pydantic import Field, SerializerFunctionWrapHandler, model_serializer

from harness.archive.reader import RunArchive
from harness.summary.declaring import TestName, declared_figures, report_test
from harness.summary.delay_bound import NisSeries, nis_series, with_delay_bounds
from harness.summary.records import SummaryRecord
from harness.summary.scoring import (
    Alarm,
    DeclaringTest,
    FaultClass,
    Judged,
    Scores,
    overlaps_fault,
    score,
)
from harness.summary.series import FdirSeries, MainWindow, SeriesWindow
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    WINDOW_TESTS,
    BaselineVerdict,
    FaultReport,
    FdirWindow,
    StateEstimate,
)
from interfaces.contracts.scenario import FdirSettings, Scenario


class Detection(SummaryRecord):
    """A fault the ground declared (a ``FaultReport``)."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("evidence",)

    spacecraft: int = Field(ge=0, description="the faulty observer; 0: the constellation")
    time_s: float = Field(description="end of the declaring window, sim s (the sequential "
                                      "test: the time of the image that crossed)")
    declared_s: float | None = Field(
        default=None, description="when the ground declared it, sim s (with ground passes: "
                                  "once the window's data came down)")
    cause: Literal["store_overflow"] | None = Field(
        default=None, description="a link fault's known cause (not scored as an alarm)")
    declared_by: Literal["ground", "neighbours"] = Field(
        default="ground", description="who declared it: the ground's FDIR, or the observers' "
                                      "neighbours by agreement aboard")
    judges: list[int] | None = Field(
        default=None, description="the neighbours that found the window failed")
    detector: Literal["window", "sequential"] = Field(
        default="window", description="what declared it: a window's tests, or the sequential "
                                      "test at an image (docs/fdir.md)")
    fault_class: FaultClass | None = Field(alias="class",
                                           description="identified class (null: not yet)")
    direction: Literal["improved", "degraded"] | None = Field(
        description="the information gain's direction in the declaring window")
    test: TestName | None = Field(
        default=None, description="the test that declared it (harness/summary/declaring.py: "
                                  "'information', 'nis_scan', 'global_check', ...; "
                                  "'identification': a class named later in its episode); "
                                  "absent: a summary before it was recorded")
    metric: float | None = Field(description="the declaring test's statistic (the information "
                                             "test: H_m,i of the declaring window)")
    threshold: float | None = Field(description="the threshold it exceeded (the information "
                                                "test: τ_i), same unit")
    evidence: dict[str, float] = Field(default_factory=dict,
                                       description="what the class rests on, by name")
    faithful: bool | None = Field(
        default=None, description="replays only: declared before the replay's uplinks left "
                                  "the flown run's (``replay.faithful_until_s``)")






class Counts(SummaryRecord):
    """Counts of windows, added field by field over runs (``a + b``)."""

    def __add__(self, other: Self) -> Self:
        return self.model_validate(
            {name: getattr(self, name) + getattr(other, name) for name in type(self).model_fields})


class ThresholdSources(Counts):
    """Nominal windows by the threshold in force."""

    model: int = Field(description="the hardware model's")
    sampled: int = Field(description="Eq. 11-12's, from sampled twins")
    floor: int = Field(description="the floor guard's")


class FailedTests(Counts):
    """Nominal windows failed on each test of the main detector (``WINDOW_TESTS``)."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("nis",)

    information: int
    plan: int
    pointing: int
    dv_rate: int
    nis: int = Field(default=0, description="absent from summaries before the NIS test")


class ModelZ(Counts):
    """Nominal standardised ratios (x − μ)/σ of the hardware model beyond 2, 3 and 4."""

    over_2: int
    over_3: int
    over_4: int
    windows: int = Field(description="nominal windows with a ratio")


class UnjudgedCounts(Counts):
    """Windows (or H_i reports) with no decision, by reason (``messages.Unjudged``; docs/fdir.md,
    "Lost is not corrupt")."""

    store_overflow: int = 0
    aboard: int = 0
    lost: int = 0
    not_heard: int = 0
    lossy: int = 0
    crosslink_loss: int = 0
    crosslink_shortfall: int = 0
    no_plan: int = 0
    camera_off: int = 0
    no_images: int = 0
    out_of_range: int = 0
    not_tracking: int = 0
    plan_unknown: int = 0
    transfer: int = 0
    excluded: int = 0

    @classmethod
    def of(cls, reasons: list[str | None]) -> UnjudgedCounts:
        return cls.model_validate({r: reasons.count(r) for r in set(reasons) if r is not None})


class ThresholdCensus(Counts):
    """``fdir_thresholds``: over the nominal windows the main detector decided, what set the
    threshold, how often each threshold lay above the floor and which tests failed; and over
    every window, why those without a decision had none."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("unjudged", "integrity_unjudged")

    nominal_windows: int
    threshold_by: ThresholdSources
    model_above_floor: int
    sampled_above_floor: int
    failed: FailedTests
    model_z: ModelZ
    unjudged: UnjudgedCounts = Field(
        default_factory=UnjudgedCounts,
        description="windows of every observer the information test could not decide, by reason")
    integrity_unjudged: UnjudgedCounts = Field(
        default_factory=UnjudgedCounts,
        description="H_i reports the data-integrity check did not judge, by reason")


class RunFdirSettings(FdirSettings):
    """``fdir_settings``: the scenario's ``[fdir]`` section and its FDI period (on disk
    first).  Summaries older than a setting lack it: its default is filled in (and named)."""

    FILLABLE: ClassVar[tuple[str, ...]] = tuple(FdirSettings.model_fields)

    fdi_period_s: float = Field(gt=0.0, description="FDI window length, s (rates.fdi_period_s)")

    @model_serializer(mode="wrap")
    def _period_first(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        d = handler(self)
        return ({"fdi_period_s": d.pop("fdi_period_s")} if "fdi_period_s" in d else {}) | d


class FdirResults(SummaryRecord):
    """The FDIR sections of a summary, from the ground's own output messages (a live run's
    archive or a replay): ``harness.summary.build.fdir_results``."""

    detections: list[Detection]
    scores: Scores = Field(description="the main detector's")
    baselines: dict[str, Scores] = Field(description="each baseline detector's, by name")
    fdir_series: FdirSeries
    fdir_thresholds: ThresholdCensus
    fdir_settings: RunFdirSettings


ARCHIVE_END = ("sim time of the archive's last message, s: where the replay stopped judging "
               "(the run's end for a whole archive; before it, for one cut short or of a run "
               "stopped early, nothing due at or after it is judged or compared: "
               "harness/replay.py)")
"""What a replay's ``archive_end_s`` is."""


class ReplayResults(FdirResults):
    """A replay's results (replay.json, ``harness.replay``): the FDIR sections as the
    replayed ground gives them (``detections`` marked ``faithful``; ``fdir_thresholds`` over
    the faithful span), and its faithfulness."""

    HEAD: ClassVar[tuple[str, ...]] = ("scenario", "seed", "replay_wall_s", "archive_end_s",
                                       "faithful_until_s", "matches_live")
    """The fields written before the FDIR sections."""

    scenario: str
    seed: int
    replay_wall_s: float = Field(description="the replay's wall time, s")
    archive_end_s: float = Field(description=ARCHIVE_END)
    faithful_until_s: float = Field(
        description="sim time of the first uplink differing from the live run's (at most "
                    "archive_end_s), s")
    matches_live: bool = Field(description="every window, report and verdict as live")
    scores_faithful: Scores = Field(description="the main detector's up to faithful_until_s")

    @model_serializer(mode="wrap")
    def _head_first(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        d = handler(self)
        return {k: d.pop(k) for k in self.HEAD if k in d} | d


class ReplaySection(SummaryRecord):
    """``replay``: how a campaign replay re-judged the run (deploy/campaign_replay.py)."""

    settings: dict[str, str] = Field(description="the settings changed (--set), as given")
    wall_s: float = Field(description="the replay's wall time, s")
    archive_end_s: float | None = Field(
        default=None, description=ARCHIVE_END + " (absent: a replay before it was recorded)")
    faithful_until_s: float = Field(
        description="sim time of the first uplink differing from the live run's (at most "
                    "archive_end_s), s")
    matches_live: bool
    scores_faithful: Scores = Field(description="the main detector's up to faithful_until_s")


def fdir_summary(archive: RunArchive, scenario: Scenario, mission: str) -> FdirResults:
    """``detections`` (the ground FDIR's fault reports) and ``scores`` against the injected
    faults (harness/summary/scoring.py; grace of one FDI window)."""
    return fdir_results(archive.of(cat.FAULT_REPORT, mission),
                        archive.of(cat.FDIR_WINDOW, mission), archive.of(cat.BASELINE, mission),
                        scenario, archived_nis(archive.of(cat.NAV_ESTIMATE, mission), scenario))


def archived_nis(estimates: list[StateEstimate], scenario: Scenario) -> NisSeries | None:
    """Where the sequential test runs, each observer's nav updates as archived (``estimates``:
    the run's; their NIS bound each fault's delay, ``harness/summary/delay_bound.py``); else
    None."""
    if scenario.fdir.detector != "sequential":
        return None
    return nis_series(estimates)


def fdir_results(reports: list[FaultReport], windows: list[FdirWindow],
                 verdicts: list[BaselineVerdict], scenario: Scenario,
                 nis: NisSeries | None = None) -> FdirResults:
    """The FDIR part of summary.json from the ground's own output messages (a live run's
    archive or a replay): detections, scores, baselines, series and settings; ``nis``: the
    nav updates the ground judged, for the delay bounds."""
    sequential = scenario.fdir.detector == "sequential"
    alarms = [Alarm(r.spacecraft, r.t_sim, r.fault_class, r.declared_s,
                    _declaring_test(r) if sequential else None) for r in reports
              if r.cause is None]  # a known cause (store overflow) is no alarm of a fault
    judged = [Judged(w.spacecraft, w.t_start_s, w.t_end_s) for w in windows
              if w.exceeded is not None]
    scores = score(scenario.faults, alarms, judged, grace_s=scenario.rates.fdi_period_s)
    by_window = {(w.spacecraft, w.t_end_s): w for w in windows}
    return FdirResults(
        detections=[detection(r, by_window.get((r.spacecraft, r.window_end_s)), scenario.fdir)
                    for r in reports],
        scores=(with_delay_bounds(scores, scenario.faults, windows, 1.0 / scenario.rates.mid_hz,
                                  nis)
                if sequential else scores),
        baselines=baseline_scores(verdicts, scenario),
        fdir_series=series_of(windows, verdicts),
        fdir_thresholds=threshold_census(windows, scenario),
        fdir_settings=RunFdirSettings.model_validate(
            {"fdi_period_s": scenario.rates.fdi_period_s, **scenario.fdir.model_dump()}))


def detection(r: FaultReport, window: FdirWindow | None, cfg: FdirSettings) -> Detection:
    """The ground's report ``r`` as a detection, with the test that declared it (``window``:
    the window it was declared on, if any) and that test's statistic and threshold."""
    test = report_test(r, window)
    metric, threshold = declared_figures(test, r, window, cfg)
    return Detection(spacecraft=r.spacecraft, time_s=r.t_sim, fault_class=r.fault_class,
                     direction=r.direction, test=test, metric=metric, threshold=threshold,
                     evidence=dict(r.evidence), declared_s=r.declared_s, declared_by="ground",
                     **({"cause": r.cause} if r.cause else {}),
                     **({"detector": r.detector} if r.detector != "window" else {}))


def _declaring_test(report: FaultReport) -> DeclaringTest:
    """What declared ``report``: a window's tests, the image scan, the NIS scan or the
    pointing run."""
    if report.detector == "sequential":
        for test in ("nis_scan", "pointing_scan"):
            if report.evidence.get(test):
                return test  # type: ignore[return-value]
    return report.detector


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
                       over_4=sum(v > 4 for v in z), windows=len(z)),
        unjudged=UnjudgedCounts.of([w.unjudged for w in windows]),
        integrity_unjudged=UnjudgedCounts.of([w.integrity_unjudged for w in windows]))


def series_of(windows: list[FdirWindow], verdicts: list[BaselineVerdict]) -> FdirSeries:
    """``fdir_series``: every decided window of each detector (``harness.summary.series``) --
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


def detection_test(d: Detection) -> TestName:
    """The test that declared ``d``: as recorded, or, for a summary written before the test
    was recorded, from the detection's own fields (a window's declaration is then taken for
    the information test's)."""
    if d.test is not None:
        return d.test
    if d.declared_by == "neighbours":
        return "neighbours"
    report = FaultReport(sender="summary", t_sim=d.time_s, spacecraft=d.spacecraft,
                         fault_class=d.fault_class, window_end_s=d.time_s,
                         evidence=d.evidence, cause=d.cause, detector=d.detector)
    return report_test(report, None)
