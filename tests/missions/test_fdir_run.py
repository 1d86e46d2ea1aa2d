"""The ground FDIR's window test in a real (in-process) run (the sequential test, the default:
tests/missions/test_fdir_sequential_run.py): a degraded camera is detected and isolated with
the metric at 1 − β (Eq. 21), the healthy observers stay far below the threshold, a
spacecraft whose link is cut is reported as a link fault, not as a performance fault, and one
that reports a corrupted H_i as a data-integrity fault."""

from __future__ import annotations

import re

import pytest

from harness.campaign.calibrate import main as calibrate_main
from harness.report import write_report
from harness.summary import RunSummary
from interfaces.contracts.messages import FaultReport, FdirWindow
from tests.conftest import recorded_run, small_scenario


@pytest.fixture(scope="module")
def fdir_run(tmp_path_factory: pytest.TempPathFactory
             ) -> tuple[list[FdirWindow], list[FaultReport], RunSummary]:
    sc = small_scenario(
        "fd", duration_s=400.0, target={"pois": 1000},
        rates={"high_hz": 5.0, "fdi_period_s": 50.0}, fdir={"detector": "window"},
        observers={"count": 3, "initial_attitude": "lvlh"},
        faults=[{"spacecraft": 2, "kind": "camera_degradation", "start_s": 0.0,
                 "magnitude": 0.5},
                {"spacecraft": 3, "kind": "link_loss", "start_s": 200.0, "end_s": 300.0},
                {"spacecraft": 1, "kind": "faulty_data", "start_s": 150.0, "magnitude": 2.0}])
    out = tmp_path_factory.mktemp("fdir")
    got, summary = recorded_run(sc, out, FdirWindow, FaultReport)
    write_report(out, sc)
    return got["FdirWindow"], got["FaultReport"], summary


Run = tuple[list[FdirWindow], list[FaultReport], RunSummary]


def test_camera_fault_detected_and_isolated(fdir_run: Run) -> None:
    windows, reports, _ = fdir_run
    judged = [w for w in windows if w.metric is not None]
    faulty = [w for w in judged if w.spacecraft == 2 and w.images >= 40]
    assert len(faulty) >= 3
    assert all(w.metric == pytest.approx(0.5, abs=0.01) and w.direction == "degraded"
               and w.exceeded for w in faulty)
    healthy = [w for w in judged if w.spacecraft != 2]
    assert healthy and all(not w.exceeded for w in healthy)
    assert max(w.metric for w in healthy if w.metric is not None) < 0.01
    perf = [r for r in reports if r.fault_class not in ("link", "data_integrity")]
    assert [r.spacecraft for r in perf] == [2]  # declared once, on the faulty one only


def test_silent_spacecraft_is_a_link_fault(fdir_run: Run) -> None:
    windows, reports, _ = fdir_run
    cut = [w for w in windows if w.spacecraft == 3 and 200.0 <= w.t_start_s < 300.0]
    assert cut and all(w.images == 0 and w.metric is None and w.exceeded is None for w in cut)
    link = [r for r in reports if r.fault_class == "link"]
    # one silent window decides on a lossless link (it could not empty one)
    assert [(r.spacecraft, r.t_sim) for r in link] == [(3, 250.0)]
    after = [w for w in windows if w.spacecraft == 3 and w.t_start_s >= 300.0]
    assert after and all(w.images > 0 and not w.exceeded for w in after)  # back, healthy


def test_summary_scores_the_run(fdir_run: Run) -> None:
    _, reports, summary = fdir_run
    assert summary.detections is not None and summary.scores is not None
    assert len(summary.detections) == len(reports)
    cam, link, data = summary.scores.per_fault
    assert cam.detected and cam.isolated and cam.spacecraft == 2
    assert cam.latency_s == min(r.t_sim for r in reports if r.spacecraft == 2)
    assert link.isolated and link.identified_class == "link" and link.identified_correctly
    # one silent 50 s window (it decides on a lossless link), declared the FDIR's latency
    # (3 s) after it: a link alarm counts when it was declared (harness/summary/scoring.py)
    assert link.latency_s == 53.0
    assert data.isolated and data.identified_class == "data_integrity"
    assert data.latency_s == 50.0  # reports at 150 and 200 s inconsistent: persistence 2
    assert summary.scores.false_alarms == 0 and summary.scores.nominal_cycles >= 4


def test_report_plots_metric_against_threshold(fdir_run: Run,
                                               tmp_path_factory: pytest.TempPathFactory) -> None:
    _, _, summary = fdir_run
    out = next(tmp_path_factory.getbasetemp().glob("fdir*"))
    report = (out / "report.md").read_text()
    assert "## FDIR" in report and (out / "fdir.png").stat().st_size > 10_000
    assert "fdir_gain.png" in report and (out / "fdir_gain.png").stat().st_size > 10_000
    assert "| camera_degradation | 2 | 0 | yes | yes |" in report
    assert summary.scores is not None
    assert f"False alarms: 0 in {summary.scores.nominal_cycles} nominal" in report
    assert "| camera_degradation, faulty_data, link_loss | H_m,i > 0, i = 1, 2, 3 |" in report
    assert "| chi2_nis |" in report and "| cusum |" in report and "| fixed_threshold |" in report
    assert "| camera |" in report  # the class and its evidence, β located at 0.5 ± 0.04
    assert re.search(r"beta_hat 0\.(4[6-9]|5[0-4])", report)


def test_camera_fault_identified(fdir_run: Run) -> None:
    _, reports, _ = fdir_run
    cam = [r for r in reports if r.spacecraft == 2]
    assert cam[0].fault_class == "camera"
    assert cam[0].evidence["beta_hat"] == pytest.approx(0.5, abs=0.03)


def test_floor_calibrated_from_the_run(tmp_path_factory: pytest.TempPathFactory,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    """The calibration command reads the archived windows and prints the floor; a missing run
    is a clear error (exit 2)."""
    out = next(tmp_path_factory.getbasetemp().glob("fdir*"))
    assert calibrate_main([str(out), "--rate", "0.01", "--skip-s", "100"]) == 0
    text = capsys.readouterr().out
    assert "nominal windows" in text and "floor for 0.01 false alarms" in text
    assert calibrate_main([str(out / "nothing")]) == 2
