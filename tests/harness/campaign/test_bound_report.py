"""The campaign report's delay-against-the-bound section (harness/campaign/bound_report.py):
its counts and medians over results.csv rows, and its plot."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from harness.campaign.bound_report import bound_lines, bounded_rows, kind_figures


def _row(kind: str, delay: float | None, bound: float | None, test: str = "sequential",
         **extra: Any) -> dict[str, Any]:
    return {"detector": "main", "kind": kind, "isolated": delay is not None,
            "window_latency_s": delay, "delay_bound_s": bound, "declaring_test": test,
            "image_divergence": None if bound is None else 14.0 / bound, "magnitude": 0.8,
            **extra}


ROWS = [_row("camera_degradation", 1.0, 1.0), _row("camera_degradation", 3.0, 1.0),
        _row("camera_degradation", 2.0, 1.0, "window"),
        _row("thruster_bias", 40.0, 10.0, "nis_scan", nis_divergence=2.0),
        _row("thruster_bias", 4.0, 10.0, "nis_scan", nis_divergence=4.0),
        _row("thruster_bias", None, 10.0),
        _row("thruster_bias", 5.0, None), _row("none", None, None),
        _row("pointing_actuator", 6.0, 2.0, "pointing_scan"),
        _row("camera_degradation", 1.0, 1.0, detector="chi2")]


def test_only_the_main_detector_s_isolated_faults_with_a_bound_count() -> None:
    assert len(bounded_rows(ROWS)) == 6


def test_a_kind_s_figures_are_its_medians_and_counts() -> None:
    camera = kind_figures([r for r in bounded_rows(ROWS) if r["kind"] == "camera_degradation"])
    assert camera == {"faults": 3, "scan": 2, "nis_scan": 0, "pointing_scan": 0, "delay": 2.0,
                      "bound": 1.0, "divergence": 14.0, "nis": None, "within": 2}


def test_the_section_has_a_row_per_kind_and_its_plot(tmp_path: Path) -> None:
    lines = bound_lines(tmp_path, ROWS)
    assert "| camera_degradation | 3 | 2 / 0 / 0 / 1 | 2 | 1.0 | 14 | - | 2 of 3 |" in lines
    assert "| thruster_bias | 2 | 0 / 2 / 0 / 0 | 22 | 10.0 | 1.4 | 3 | 1 of 2 |" in lines
    assert "| pointing_actuator | 1 | 0 / 0 / 1 / 0 | 6 | 2.0 | 7 | - | 0 of 1 |" in lines
    assert (tmp_path / "bound.png").stat().st_size > 0
    assert bound_lines(tmp_path, [_row("thruster_bias", 5.0, None)]) == []
