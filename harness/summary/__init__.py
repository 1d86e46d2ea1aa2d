"""The type of a run's summary.json (docs/contracts.md): :class:`RunSummary` and the records
of its sections, read from and written to the file through pydantic.

``harness.summary.build`` builds and writes it; the run report, scoring, the campaign
report and the campaign replay read it through these records.  On disk it stays the JSON it
always was (``fdir_series`` rows as positional arrays), and summaries written before a field
existed still load: the field is filled in with its default and named in
:attr:`RunSummary.filled`.
"""

from harness.summary.access import AccessAudit
from harness.summary.archive_info import (
    BUS_HEADER,
    ArchiveInfo,
    LostMessages,
    MessageCounts,
    SegmentRecord,
)
from harness.summary.control import GncStats
from harness.summary.coverage import AssignmentRecord, CoverageSummary
from harness.summary.document import (
    OTHER_TESTS_FLAG,
    RunSummary,
    SummaryError,
)
from harness.summary.execution import ExecRecord, PaceRecord, SimRecord
from harness.summary.fault_events import FaultEventRecord
from harness.summary.fdir import (
    Detection,
    FailedTests,
    FdirResults,
    ModelZ,
    ReplayResults,
    ReplaySection,
    RunFdirSettings,
    ThresholdCensus,
    ThresholdSources,
)
from harness.summary.nav import NavStats
from harness.summary.neighbours import (
    Disagreements,
    NeighboursSummary,
    NeighbourWindows,
)
from harness.summary.onboard import (
    OnboardEventRecord,
    OnboardFaultRecord,
    OnboardFdirSummary,
)
from harness.summary.records import Figure, SummaryRecord
from harness.summary.recovery import RecoveryComparison
from harness.summary.scoring import FaultClass, FaultScore, Scores
from harness.summary.series import FdirSeries, MainWindow, SeriesWindow

__all__ = [
    "BUS_HEADER", "OTHER_TESTS_FLAG", "AccessAudit", "ArchiveInfo", "AssignmentRecord",
    "CoverageSummary", "Detection", "ExecRecord", "FailedTests", "FaultClass", "FaultEventRecord",
    "FaultScore", "FdirResults", "FdirSeries", "Figure", "GncStats", "LostMessages", "MainWindow",
    "MessageCounts", "ModelZ", "NavStats", "Disagreements", "NeighboursSummary",
    "NeighbourWindows", "OnboardEventRecord", "OnboardFaultRecord",
    "OnboardFdirSummary", "RecoveryComparison", "ReplayResults",
    "ReplaySection", "PaceRecord", "RunFdirSettings", "RunSummary", "Scores", "SegmentRecord",
    "SeriesWindow", "SimRecord", "SummaryError", "SummaryRecord", "ThresholdCensus",
    "ThresholdSources",
]
