"""The global check in a real (in-process) run: a calibration error common to every camera
(``camera_calibration``: every precision scaled by 0.6) is declared once on the constellation
(spacecraft 0, ``common_mode``), not as a camera fault of each observer, and the run's
summary scores it as detected, isolated and identified."""

from __future__ import annotations

from typing import Any

import pytest

from harness.summary import RunSummary
from interfaces.contracts.messages import ConstellationWindow, FaultReport, FdirWindow
from tests.conftest import recorded_run, small_scenario

ONSET_S = 150.0


@pytest.fixture(scope="module")
def common_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, list[Any]],
                                                                   RunSummary]:
    sc = small_scenario(
        "cm", duration_s=350.0, target={"pois": 1000},
        rates={"fdi_period_s": 50.0}, observers={"count": 4, "initial_attitude": "lvlh"},
        faults=[{"spacecraft": 0, "kind": "camera_calibration", "start_s": ONSET_S,
                 "magnitude": 0.6}])
    return recorded_run(sc, tmp_path_factory.mktemp("common"), FdirWindow, FaultReport,
                        ConstellationWindow)


def test_common_mode_fault_declared_on_the_constellation_only(common_run: Any) -> None:
    got, _ = common_run
    reports: list[FaultReport] = got["FaultReport"]
    assert [(r.spacecraft, r.fault_class) for r in reports] == [(0, "common_mode")]
    assert ONSET_S <= reports[0].t_sim <= ONSET_S + 150.0  # at its first image, scanned
    assert reports[0].direction == "degraded"


def test_constellation_windows_before_and_after_onset(common_run: Any) -> None:
    got, _ = common_run
    windows: list[ConstellationWindow] = [w for w in got["ConstellationWindow"]
                                          if w.ratio is not None]
    before = [w for w in windows if w.t_end_s <= ONSET_S]
    after = [w for w in windows if w.t_start_s >= ONSET_S]
    assert before and all(not w.exceeded for w in before)
    assert after and all(w.common_mode and w.ratio == pytest.approx(0.6, abs=0.02)
                         for w in after)
    assert after[-1].shortfall > before[-1].shortfall  # Eq. 6's running H - H_nom grows
    # every observer's information test failed, but the window is the constellation's
    faulty = [w for w in got["FdirWindow"] if w.t_start_s >= ONSET_S and w.metric is not None]
    assert faulty and all("information" in w.failed and w.exceeded is False for w in faulty)


def test_summary_scores_the_common_mode_fault(common_run: Any) -> None:
    _, summary = common_run
    assert summary.scores is not None
    (f,) = summary.scores.per_fault
    assert f.detected and f.isolated and f.identified_correctly
    assert f.identified_class == "common_mode" and f.spacecraft == 0
    assert summary.scores.false_alarms == 0
