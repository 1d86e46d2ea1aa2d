"""summary.json's FDIR sections: the ground's declarations (``detections``), their scores
against the injected faults (``scores``, ``baselines``), the decided windows
(``fdir_series``), what set the thresholds (``fdir_thresholds``) and the detector's settings
(``fdir_settings``); and a replay's results (``harness.replay``), which a campaign replay
writes into the run's summary."""

from __future__ import annotations

from typing import Any, ClassVar, Literal, Self

from pydantic import Field, SerializerFunctionWrapHandler, model_serializer

from harness.summary.records import Figure, SummaryRecord
from harness.summary.series import FdirSeries
from interfaces.contracts.scenario import FaultKind, FdirSettings

FaultClass = Literal["actuator", "camera", "state_sensor", "link", "data_integrity",
                     "common_mode"]
"""The classes the ground identifies a fault as (``FaultReport.fault_class``)."""


class Detection(SummaryRecord):
    """A fault the ground declared (a ``FaultReport``)."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("evidence",)

    spacecraft: int = Field(ge=0, description="the faulty observer; 0: the constellation")
    time_s: float = Field(description="end of the declaring window, sim s")
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
    fault_class: FaultClass | None = Field(alias="class",
                                           description="identified class (null: not yet)")
    direction: Literal["improved", "degraded"] | None = Field(
        description="the information gain's direction in the declaring window")
    metric: float | None = Field(description="H_m,i of the declaring window (dimensionless)")
    threshold: float | None = Field(description="τ_i it exceeded, same unit")
    evidence: dict[str, float] = Field(default_factory=dict,
                                       description="what the class rests on, by name")
    faithful: bool | None = Field(
        default=None, description="replays only: declared before the replay's uplinks left "
                                  "the flown run's (``replay.faithful_until_s``)")


class FaultScore(SummaryRecord):
    """How a detector did on one injected fault (harness/summary/scoring.py)."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("identification_latency_s",)

    spacecraft: int = Field(ge=0, description="the faulty observer; 0: common mode")
    kind: FaultKind
    start_s: float = Field(description="onset, sim s")
    detected: bool = Field(description="any alarm while the fault was active")
    isolated: bool = Field(description="an alarm naming its spacecraft")
    latency_s: float | None = Field(description="onset to the first (isolating) alarm, s")
    identified_class: FaultClass | None = Field(
        description="class of the first isolating alarm that names one")
    expected_class: FaultClass
    identified_correctly: bool
    identification_latency_s: float | None = Field(
        default=None, description="onset to the first alarm naming its class, s")
    declared_latency_s: float | None = Field(
        default=None, description="onset to the first (isolating) alarm's declaration, s: "
                                  "what the ground knew when (with ground passes, the gap "
                                  "to the pass is in it)")


class Scores(SummaryRecord):
    """A detector's scores over a run: per injected fault and false alarms."""

    per_fault: list[FaultScore] = Field(description="in scenario order")
    false_alarms: int = Field(ge=0, description="alarms on a spacecraft with no active fault")
    nominal_cycles: int = Field(ge=0, description="judged FDI windows overlapping no fault")
    false_alarm_rate: Figure = Field(description="false alarms per nominal cycle")
    false_alarms_per_hour: Figure = Field(description="per hour of nominal spacecraft time")


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


class ThresholdCensus(Counts):
    """``fdir_thresholds``: over the nominal windows the main detector decided, what set the
    threshold, how often each threshold lay above the floor and which tests failed."""

    nominal_windows: int
    threshold_by: ThresholdSources
    model_above_floor: int
    sampled_above_floor: int
    failed: FailedTests
    model_z: ModelZ


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


class ReplayResults(FdirResults):
    """A replay's results (replay.json, ``harness.replay``): the FDIR sections as the
    replayed ground gives them (``detections`` marked ``faithful``; ``fdir_thresholds`` over
    the faithful span), and its faithfulness."""

    HEAD: ClassVar[tuple[str, ...]] = ("scenario", "seed", "replay_wall_s", "faithful_until_s",
                                       "matches_live")
    """The fields written before the FDIR sections."""

    scenario: str
    seed: int
    replay_wall_s: float = Field(description="the replay's wall time, s")
    faithful_until_s: float = Field(
        description="sim time of the first uplink differing from the live run's, s")
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
    faithful_until_s: float = Field(
        description="sim time of the first uplink differing from the live run's, s")
    matches_live: bool
    scores_faithful: Scores = Field(description="the main detector's up to faithful_until_s")
