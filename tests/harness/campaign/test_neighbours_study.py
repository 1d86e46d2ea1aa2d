"""The neighbours' study (harness/campaign/neighbours_study.py) on constructed run summaries: the
runs paired by group and index across the central and neighbours variants, each side's
latency from onset to its declaration, the neighbours' false alarms per neighbour-window with
the 95% bound, and the rulings."""

from __future__ import annotations

from pathlib import Path

from harness.campaign.neighbours_study import cases, write_neighbours_study
from harness.summary import RunSummary
from tests.harness.campaign.test_report import _fault, _scores, _summary


def _neighbours(per_fault: list[dict[str, object]], false_alarms: int, windows: int,
                upheld: int) -> dict[str, object]:
    return {"agree": 2, "scores": _scores(per_fault, false_alarms, windows),
            "windows": {"neighbour_windows": windows, "judge_windows": 4 * windows,
                        "nominal_judge_windows": 4 * windows, "nominal_exceeded": 1},
            "disagreements": {"overruled": 0, "upheld": upheld, "unruled": 0,
                              "ground_only": 0},
            "rulings": {"2@540": "upheld"} if upheld else {}}


def _write(out: Path, rid: str, summary: RunSummary) -> str:
    (out / "runs" / rid).mkdir(parents=True)
    summary.write(out / "runs" / rid / "summary.json")
    return rid


def test_the_study_puts_the_ground_alone_beside_the_neighbours(tmp_path: Path) -> None:
    late = {**_fault(2, "thruster_bias", 520.0, True, 20.0, "actuator", "actuator"),
            "declared_latency_s": 5444.0}
    quick = {**_fault(2, "thruster_bias", 520.0, True, 20.0, None, "actuator"),
             "declared_latency_s": 24.0}
    fault = {"injected_faults": [{"spacecraft": 2, "kind": "thruster_bias", "start_s": 520.0,
                                  "magnitude": 0.4}]}
    ids = [
        _write(tmp_path, "thruster-central-0000", _summary("a", {
            **fault, "scores": _scores([late], 0, 90)})),
        _write(tmp_path, "thruster-neighbours-0000", _summary("b", {
            **fault, "scores": _scores([late], 0, 90),
            "neighbours": _neighbours([quick], 0, 400, 1),
            "detections": [{"spacecraft": 2, "time_s": 540.0, "declared_s": 544.0,
                            "class": None, "direction": None, "metric": None,
                            "threshold": None, "declared_by": "neighbours", "judges": [1, 3]}]})),
        _write(tmp_path, "nominal-central-0000", _summary("c", {
            "injected_faults": [], "scores": _scores([], 0, 200)})),
        _write(tmp_path, "nominal-neighbours-0000", _summary("d", {
            "injected_faults": [], "scores": _scores([], 0, 200),
            "neighbours": _neighbours([], 1, 1000, 0)})),
    ]
    from harness.campaign.rescore import load_runs
    paired = cases(load_runs(tmp_path, ids))
    assert [(c.group, c.index, c.central is not None, c.neighbours is not None)
            for c in paired] == [("nominal", "0000", True, True), ("thruster", "0000", True, True)]
    text = write_neighbours_study(tmp_path, ids).read_text()
    assert "| thruster | 1 | 1/1: 5444 / 5444 / 5444 | 1/1: 24 / 24 / 24 |" in text
    assert "Over the nominal runs: 1 in 1000 (1.00e-03 per neighbour-window; 95% ≤ 4.73e-03)" \
        in text
    assert "Over every nominal window of every run: 1 in 1400" in text
    assert "| thruster-0000 | sc2 thruster_bias | 520 | 5444 | 24: 1, 3 | 5444 | upheld |" in text
    assert (tmp_path / "study" / "latency.png").stat().st_size > 0
