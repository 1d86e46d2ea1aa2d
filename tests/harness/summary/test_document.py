"""summary.json's type (harness/summary) without a run: a failed run's summary holds
its head alone and writes back as it was; a main-detector row of five values (written before
the other-tests flag) loads with the flag filled; the records' classes and tests are the
messages'; the archive's segments and lost messages are given only when there are some.  The
real run's summary is read in tests/missions/test_run_summary.py."""

from __future__ import annotations

import json
import typing
from pathlib import Path

from ground.archive.recorder import McapRecorder
from harness.archive.reader import load_run
from harness.report import archive_end, archive_section
from harness.summary import (
    FailedTests,
    FaultClass,
    LostMessages,
    MainWindow,
    RunSummary,
    SegmentRecord,
)
from harness.summary.archive_info import archive_info
from interfaces.contracts.messages import WINDOW_TESTS, FaultReport, StateEstimate
from interfaces.runtime.encoding import encode


def test_a_failed_runs_summary_has_the_head_alone(tmp_path: Path) -> None:
    """deploy.campaign.record_failure's summary: no archive, so no figures; written back
    without the absent sections."""
    text = json.dumps({"scenario": "x", "seed": 1, "status": "failed", "error": "killed",
                       "injected_faults": []}, indent=2) + "\n"
    (tmp_path / "summary.json").write_text(text)
    s = RunSummary.read(tmp_path / "summary.json")
    assert s.scores is None and s.fdir_series is None and s.wall_s is None and s.filled == []
    s.write(tmp_path / "again.json")
    assert (tmp_path / "again.json").read_text() == text


def test_the_records_follow_the_messages() -> None:
    """The census counts each test of the main detector; the classes are the FDIR's."""
    assert tuple(FailedTests.model_fields) == WINDOW_TESTS
    assert set(typing.get_args(FaultClass)) == set(typing.get_args(
        typing.get_args(FaultReport.model_fields["fault_class"].annotation)[0]))


def test_a_main_window_from_a_five_value_row() -> None:
    old = MainWindow.model_validate([2, 0.0, 30.0, 0.2, 0.05])
    assert old.other_tests_failed is False and "other_tests_failed" not in old.model_fields_set
    assert old.exceeded() and not old.exceeded(scale=10.0)
    assert old.model_dump() == [2, 0.0, 30.0, 0.2, 0.05]
    new = MainWindow.model_validate([2, 0.0, 30.0, 0.01, 0.05, 1.0])
    assert new.exceeded(scale=10.0) and new.model_dump() == [2, 0.0, 30.0, 0.01, 0.05, 1.0]


def _archive(path: Path, seqs: list[int]) -> None:
    """An archive file of nav estimates of sc1 numbered ``seqs`` (at seq / 10 s)."""
    with McapRecorder(path) as rec:
        for seq in seqs:
            msg = StateEstimate(sender="sc1", seq=seq, t_sim=seq / 10, spacecraft=1, x=[0.0] * 6,
                                P=[[float(i == j) for j in range(6)] for i in range(6)])
            rec.record("insp/m/sc/1/nav/estimate", "StateEstimate", encode(msg))


def test_a_clean_archive_says_what_it_always_said(tmp_path: Path) -> None:
    _archive(tmp_path / "run.mcap", [1, 2, 3])
    info = archive_info(load_run(tmp_path / "run.mcap"))
    assert info.to_json(indent=0) == '{\n"truncated": false\n}'
    assert archive_section(RunSummary(scenario="x", seed=1, status="completed", error=None,
                                       injected_faults=[], archive=info)) == []


def test_segments_and_lost_messages_are_named_by_topic(tmp_path: Path) -> None:
    """A restarted recorder's two files and the messages sent between: in summary.json (read
    back as written) and report.md."""
    _archive(tmp_path / "run.mcap", [1, 2, 3])
    _archive(tmp_path / "run-1.mcap", [7, 8])
    info = archive_info(load_run(tmp_path / "run.mcap"))
    assert info.segments == [SegmentRecord(file="run.mcap", truncated=False),
                             SegmentRecord(file="run-1.mcap", truncated=False)]
    assert info.lost == LostMessages(total=3, by_topic={"nav/estimate": 3})
    summary = RunSummary(scenario="x", seed=1, status="degraded", error="recorder killed",
                         injected_faults=[], archive=info)
    summary.write(tmp_path / "summary.json")
    again = RunSummary.read(tmp_path / "summary.json")
    assert again.archive == info and again.filled == []
    assert "| nav/estimate | 3 |" in archive_section(again)
    assert "Segments: run.mcap, run-1.mcap." in archive_section(again)


def test_a_cut_archive_says_where_it_ends(tmp_path: Path) -> None:
    """A file cut at half its bytes: summary.json's ``archive`` gives the sim time of its last
    message and where the file was cut, and the report says it before anything else."""
    with McapRecorder(tmp_path / "full.mcap", chunk_size=1024) as rec:
        for seq in range(1, 400):
            msg = StateEstimate(sender="sc1", seq=seq, t_sim=seq / 10, spacecraft=1,
                                x=[seq * 0.1234567 + i for i in range(6)],
                                P=[[float(i == j) for j in range(6)] for i in range(6)])
            rec.record("insp/m/sc/1/nav/estimate", "StateEstimate", encode(msg))
    data = (tmp_path / "full.mcap").read_bytes()
    (tmp_path / "run.mcap").write_bytes(data[:len(data) // 2])
    archive = load_run(tmp_path / "run.mcap")
    info = archive_info(archive)
    assert info.truncated and info.end_s == archive.end_s and 0.0 < (info.end_s or 0) < 39.9
    assert info.cut is not None and info.cut.startswith("run.mcap read up to byte ")
    assert f"of {len(data) // 2}: file ends before its footer" in info.cut
    summary = RunSummary(scenario="x", seed=1, duration_s=39.9, status="completed", error=None,
                         injected_faults=[], archive=info)
    summary.write(tmp_path / "summary.json")
    again = RunSummary.read(tmp_path / "summary.json")
    assert again.archive == info
    (line, _) = archive_end(again)
    assert line.startswith(f"The archive ends at {info.end_s} s of the run's 39.9 s (run.mcap ")
    assert archive_end(RunSummary(scenario="x", seed=1, status="completed", error=None,
                                  injected_faults=[],
                                  archive=archive_info(load_run(tmp_path / "full.mcap")))) == []
