"""A run's archive read once, in one pass and bounded memory, for its summary and report.

A two-orbit run archives about 4 GB of JSON, 1.7 GB of it camera images and as much again the
observations that repeat them; held whole and decoded, the summary of such a run needed 13 GB.
The digest keeps only what the summary and report read: the camera images are fused into the
coverage as they stream past (:class:`harness.summary.coverage.CoverageFuser`), the cumulative
counters (ticks, executive and link statistics) keep their last record, the truth is packed into
arrays (:class:`harness.summary.truth_table.TruthTable`), and the bulk neither reads
(observations, attitude sensors, wheel commands, lockstep answers, heartbeats) is counted and
dropped.

A one-process run builds the same digest as it goes (:class:`LiveDigest`, fed the samples the
recorder is given): no second read of the file, and the images fused from the message objects
rather than their JSON.  ``tests/missions/test_digest_run.py`` checks that both give the same
summary.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from ground.archive.recorder import Pending, prepared
from harness.archive.live import LiveArchive
from harness.archive.reader import Record, RecordSink, RunArchive, load_run
from harness.summary.control import GncSeries, gnc_series
from harness.summary.coverage import Coverage, CoverageFuser, camera_images, coverage
from harness.summary.nav import NavErrors, nav_errors
from harness.summary.truth_table import TruthTable, TruthTableBuilder
from interfaces.contracts import catalogue as cat
from interfaces.contracts.scenario import Scenario
from interfaces.runtime.transport import Sample


@dataclass
class LastRecords:
    """A record sink keeping, per (key, type name), the last record and the count."""

    last: dict[tuple[str, str], Record] = field(default_factory=dict)
    counts: dict[tuple[str, str], int] = field(default_factory=dict)

    def __call__(self, rec: Record) -> None:
        k = (rec.key, rec.type_name)
        self.last[k] = rec
        self.counts[k] = self.counts.get(k, 0) + 1


@dataclass
class RunDigest:
    """What a run's summary and report read: the archive without the bulk, the coverage, the
    truth as arrays, and the last record (and count) of each tick and statistics key.  The
    navigation and GNC evaluations are computed once and shared by the summary and the report."""

    archive: RunArchive
    coverage: Coverage
    counters: LastRecords
    truth: TruthTable
    _nav: dict[int, NavErrors] | None = None
    _gnc: dict[int, GncSeries] | None = None

    def nav_errors(self, mission: str) -> dict[int, NavErrors]:
        if self._nav is None:
            self._nav = nav_errors(self.archive, mission, self.truth)
        return self._nav

    def gnc_series(self, scenario: Scenario, mission: str) -> dict[int, GncSeries]:
        if self._gnc is None:
            self._gnc = gnc_series(self.archive, scenario, mission, self.truth)
        return self._gnc


def counter_keys(mission: str) -> list[str]:
    """Keys whose last message is all that counts (cumulative) and the tick key (counted)."""
    return [cat.TICK.key(mission), cat.EXEC_STATS.every(mission), cat.LINK_STATS.every(mission)]


def unread_keys(mission: str) -> list[str]:
    """The bulk of an archive that neither the summary nor the report reads."""
    return [t.every(mission) for t in (cat.OBSERVATIONS, cat.ATTITUDE_SENSORS, cat.RELNAV,
                                       cat.WHEELS, cat.TICK_DONE, cat.HEARTBEAT)]


def _drop(_rec: Record) -> None:
    """Sink of the records nobody reads (they are still counted by the archive)."""


def _sinks(scenario: Scenario, mission: str
           ) -> tuple[CoverageFuser, LastRecords, TruthTableBuilder, dict[str, RecordSink]]:
    """The digest's builders and the key expressions streamed to them."""
    fuser = CoverageFuser(scenario)
    counters = LastRecords()
    truth = TruthTableBuilder()
    stream = {camera_images(mission): fuser.add_record, cat.TRUTH.key(mission): truth.add_record,
              **dict.fromkeys(counter_keys(mission), counters),
              **dict.fromkeys(unread_keys(mission), _drop)}
    return fuser, counters, truth, stream


def digest_run(path: Path, scenario: Scenario, mission: str) -> RunDigest:
    """Read ``path`` once for the summary and report (see the module docstring)."""
    fuser, counters, truth, stream = _sinks(scenario, mission)
    archive = load_run(path, stream=stream)
    return RunDigest(archive, fuser.finish(archive, mission), counters, truth.finish())


class Recorder(Protocol):
    """What takes a prepared sample for the file (McapRecorder, RecorderProcess)."""

    def take(self, pending: Pending) -> None: ...


class LiveDigest:
    """:func:`digest_run`'s digest built as a one-process run goes: give it every sample the
    recorder writes (``take``, prepared once for both), in the same order; ``finish`` after the
    run.  ``path`` and ``metadata``: the archive's file and the metadata written into it."""

    def __init__(self, scenario: Scenario, mission: str, path: Path,
                 metadata: dict[str, dict[str, str]]) -> None:
        self._fuser, self._counters, self._truth, stream = _sinks(scenario, mission)
        self._archive = LiveArchive(path, metadata, stream)
        self._mission = mission

    def tap(self, recorder: Recorder) -> Callable[[Sample], None]:
        """A sample handler giving each sample to ``recorder`` and to this digest, prepared
        once for both."""
        def handler(sample: Sample) -> None:
            pending = prepared(sample)
            recorder.take(pending)
            self._archive.take(pending, sample.message)

        return handler

    def finish(self) -> RunDigest:
        archive = self._archive.finish()
        return RunDigest(archive, self._fuser.finish(archive, self._mission), self._counters,
                         self._truth.finish())


def digest_archive(archive: RunArchive, scenario: Scenario, mission: str) -> RunDigest:
    """The same from an archive already held whole."""
    counters = LastRecords()
    for expr in counter_keys(mission):
        for rec in archive.records(expr):
            counters(rec)
    return RunDigest(archive, coverage(archive, scenario, mission), counters,
                     TruthTable.from_archive(archive, mission))
