"""``RunSummary``: the type of a run's summary.json (docs/contracts.md), read and written."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import Field, ValidationError

from harness.destination import write_whole
from harness.summary.access import AccessAudit
from harness.summary.archive_info import ArchiveInfo, MessageCounts
from harness.summary.control import GncStats
from harness.summary.coverage import CoverageSummary
from harness.summary.execution import ExecRecord, SimRecord
from harness.summary.fault_events import FaultEventRecord
from harness.summary.fdir import (
    Detection,
    FdirResults,
    ReplaySection,
    RunFdirSettings,
    ThresholdCensus,
)
from harness.summary.ground_contact import GroundContact
from harness.summary.nav import NavEntry
from harness.summary.neighbours import NeighboursSummary
from harness.summary.onboard import OnboardFdirSummary
from harness.summary.records import SummaryRecord, filled_fields
from harness.summary.recovery import RecoveryComparison
from harness.summary.scoring import Scores
from harness.summary.series import FdirSeries
from interfaces.contracts.errors import describe
from interfaces.contracts.messages import LinkCounter, TelemetryStatus
from interfaces.contracts.scenario import Fault

OTHER_TESTS_FLAG = "fdir_series.main[].other_tests_failed"
"""The field :attr:`RunSummary.filled` names when the main detector's windows predate the
other tests' flag (re-scored from them, it sees the information test alone)."""


class SummaryError(ValueError):
    """A summary.json that cannot be read as a :class:`RunSummary`."""


class RunSummary(SummaryRecord):
    """A run's summary.json.  Every run has the fields up to ``injected_faults`` (a run that
    died outside itself has only some: ``deploy.campaign.record_failure``); the rest come from
    its archive, and are absent (None) when it could not be read (``archive_error``), and from
    outside it (``access``, ``recovery``, ``replay``).  Fields are written in this order, only
    those given, as the builder gave them or the file held them."""

    scenario: str = Field(description="scenario name")
    seed: int
    transport: Literal["inproc", "zenoh"] | None = None
    duration_s: float | None = Field(default=None, description="scenario duration, sim s")
    wall_s: float | None = Field(default=None, description="the run's wall time, s")
    status: Literal["completed", "degraded", "failed", "interrupted"]
    error: str | None
    injected_faults: list[Fault] = Field(description="as in the scenario")
    archive: ArchiveInfo | None = None
    ticks: int | None = Field(default=None, description="lockstep ticks archived")
    t_sim_final_s: float | None = Field(default=None, description="last tick's sim time, s")
    messages: MessageCounts | None = None
    nav: dict[str, NavEntry] | None = Field(default=None, description="by observer")
    gnc: dict[str, GncStats] | None = Field(default=None, description="by observer")
    coverage: CoverageSummary | None = None
    links: list[LinkCounter] | None = Field(default=None, description="every directed link")
    ground_contact: GroundContact | None = Field(
        default=None, description="the passes and what waited for them (absent: the ground "
                                  "heard continuously)")
    exec: dict[str, ExecRecord] | None = Field(default=None, description="by node")
    telemetry: list[TelemetryStatus.Entry] | None = Field(
        default=None, description="the ground's telemetry monitor's last status, by observer")
    sim: SimRecord | None = None
    fault_events: list[FaultEventRecord] | None = None
    detections: list[Detection] | None = None
    scores: Scores | None = Field(default=None, description="the main detector's")
    baselines: dict[str, Scores] | None = Field(default=None,
                                                description="each baseline detector's")
    fdir_series: FdirSeries | None = None
    fdir_thresholds: ThresholdCensus | None = None
    fdir_settings: RunFdirSettings | None = None
    onboard_fdir: OnboardFdirSummary | None = Field(
        default=None, description="what the onboard FDIR did (absent: it was off)")
    neighbours: NeighboursSummary | None = Field(
        default=None, description="what the neighbours' FDIR did (absent: it was off)")
    real_time_factor: float | None = Field(default=None,
                                           description="sim s per wall s (null: no wall time)")
    archive_error: str | None = Field(default=None, description="why the archive was unread")
    access: AccessAudit | None = None
    recovery: RecoveryComparison | None = None
    replay: ReplaySection | None = None

    @property
    def filled(self) -> list[str]:
        """The fields this summary lacked, filled in on load with their defaults (it predates
        them), as dotted paths (``[]``: in some item of a list), e.g. ``OTHER_TESTS_FLAG``.
        Not part of the JSON: the summary is written back without them."""
        return list(dict.fromkeys(filled_fields(self)))

    def set_fdir(self, fdir: FdirResults) -> None:
        """Set the FDIR sections (a live run's, or a replay's in their place)."""
        self.detections = fdir.detections
        self.scores = fdir.scores
        self.baselines = fdir.baselines
        self.fdir_series = fdir.fdir_series
        self.fdir_thresholds = fdir.fdir_thresholds
        self.fdir_settings = fdir.fdir_settings

    def write(self, path: Path) -> None:
        """Write the summary to ``path`` (indent 2, a final newline), whole or not at all: it
        is written beside and renamed, so a full disk leaves no empty or cut summary."""
        write_whole(path, self.to_json() + "\n")

    @classmethod
    def read(cls, path: Path) -> RunSummary:
        """The summary in ``path``.  Raises OSError, or SummaryError naming the file and,
        from pydantic, each field at fault."""
        try:
            return cls.model_validate_json(path.read_bytes())
        except ValidationError as e:
            raise SummaryError(describe(e, f"{path}: not a valid summary.json", cls)) from None
