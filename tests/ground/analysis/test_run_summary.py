"""summary.json's type (ground/analysis/run_summary) without a run: a failed run's summary holds
its head alone and writes back as it was; a main-detector row of five values (written before
the other-tests flag) loads with the flag filled; the records' classes and tests are the
messages'.  The real run's summary is read in tests/missions/test_run_summary.py."""

from __future__ import annotations

import json
import typing
from pathlib import Path

from ground.analysis.run_summary import FailedTests, FaultClass, MainWindow, RunSummary
from interfaces.contracts.messages import WINDOW_TESTS, FaultReport


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
