"""The campaign report by drawn dimension (harness/campaign/dimensions.py, rendered by
harness/campaign/report.py) on constructed run summaries, each with the drawn.json a campaign
run writes: bins of choices and ranges, every figure of every bin against a hand count, the
failed runs counted apart, the worst bin marked, report.md's section and dimensions.json."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from harness.campaign.dimensions import Binning, by_dimension, union
from harness.campaign.report import write_campaign_report
from harness.campaign.rescore import false_alarm_bound, fault_rows, load_runs
from tests.harness.campaign.test_report import _fault, _scores, _summary, _write

DOMAINS = {"mission": {"choose": ["nominal", "default"]},
           "observers.count": {"min": 2, "max": 8, "integer": True},
           "fault.phase": {"choose": ["inspection", "transfer"]}}


def _neighbours(false_alarms: int, windows: int) -> dict[str, Any]:
    return {"agree": 2, "scores": _scores([], false_alarms, windows),
            "windows": {"neighbour_windows": windows, "judge_windows": windows,
                        "nominal_judge_windows": windows, "nominal_exceeded": 0},
            "disagreements": {"overruled": 0, "upheld": 0, "unruled": 0, "ground_only": 0}}


def _faulty(sc: int, kind: str, start: float, fault: dict[str, object], fa: int, windows: int
            ) -> dict[str, Any]:
    return {"injected_faults": [{"spacecraft": sc, "kind": kind, "start_s": start,
                                 "magnitude": 0.5}],
            "scores": _scores([fault], fa, windows)}


def _drawn(out: Path, rid: str, drawn: dict[str, Any]) -> str:
    (out / "runs" / rid / "drawn.json").write_text(json.dumps(
        {"drawn": drawn, "domains": {k: DOMAINS[k] for k in drawn}}))
    return rid


@pytest.fixture()
def campaign(tmp_path: Path) -> Path:
    """r1, r4: the paper's set-up, 2 and 3 observers, faults in inspection (both isolated at
    20 and 40 s, one identified); r2: the default mission, 5 observers, a fault in transfer
    missed in the window that could judge it; r3: the default mission, 8 observers, nominal;
    r5: the default mission, 8 observers, failed."""
    _write(tmp_path, "r1", {**_faulty(1, "thruster_bias", 100.0, _fault(
        1, "thruster_bias", 100.0, True, 20.0, "actuator", "actuator"), 0, 10),
        "neighbours": _neighbours(1, 100)}, group="g")
    _write(tmp_path, "r2", {**_faulty(2, "camera_degradation", 900.0, _fault(
        2, "camera_degradation", 900.0, False, None, None, "camera"), 1, 20),
        "fdir_series": {"main": [[2, 870.0, 900.0, 0.01, 0.05, 0.0],
                                 [2, 900.0, 930.0, 0.01, 0.05, 0.0]]}}, group="g")
    _write(tmp_path, "r3", {"injected_faults": [], "scores": _scores([], 2, 30)}, group="n")
    _write(tmp_path, "r4", _faulty(3, "pointing_actuator", 50.0, _fault(
        3, "pointing_actuator", 50.0, True, 40.0, "camera", "actuator"), 0, 10), group="g")
    d = tmp_path / "runs" / "r5"
    d.mkdir(parents=True)
    _summary("r5", {"injected_faults": []}).model_copy(
        update={"status": "failed", "error": "boom"}).write(d / "summary.json")
    _drawn(tmp_path, "r1", {"mission": "nominal", "observers.count": 2,
                            "fault.phase": "inspection"})
    _drawn(tmp_path, "r2", {"mission": "default", "observers.count": 5,
                            "fault.phase": "transfer"})
    _drawn(tmp_path, "r3", {"mission": "default", "observers.count": 8})
    _drawn(tmp_path, "r4", {"mission": "nominal", "observers.count": 3,
                            "fault.phase": "inspection"})
    _drawn(tmp_path, "r5", {"mission": "default", "observers.count": 8})
    return tmp_path


IDS = ["r1", "r2", "r3", "r4", "r5"]


def test_bins_of_choices_and_ranges() -> None:
    assert Binning({"choose": [True, False]}).labels() == ["true", "false"]
    assert Binning({"choose": [True, False]}).index(False) == 1
    wide = Binning({"min": 2, "max": 8, "integer": True})
    assert wide.labels() == ["2–3", "4–5", "6–7", "8"]
    assert [wide.index(v) for v in range(2, 9)] == [0, 0, 1, 1, 2, 2, 3]
    assert Binning({"min": 1, "max": 3, "integer": True}).labels() == ["1", "2", "3"]
    floats = Binning({"min": 10.0, "max": 25.0, "integer": False})
    assert floats.labels() == ["10–13.75", "13.75–17.5", "17.5–21.25", "21.25–25"]
    assert [floats.index(v) for v in (10.0, 13.8, 25.0, 26.0)] == [0, 1, 3, None]
    assert union({"choose": ["a"]}, {"choose": ["b", "a"]}) == {"choose": ["a", "b"]}
    assert union({"min": 2, "max": 4, "integer": True},
                 {"min": 1.5, "max": 3, "integer": False}) == \
        {"min": 1.5, "max": 4, "integer": False}


def test_every_figure_of_every_bin_against_a_hand_count(campaign: Path) -> None:
    loaded = load_runs(campaign, IDS)
    rows = fault_rows([r for r in loaded if r.summary.status == "completed"])
    dims = {d.name: d for d in by_dimension(loaded, rows)}
    assert list(dims) == ["mission", "observers.count", "fault.phase"]
    nominal, default = dims["mission"].bins
    assert (nominal.label, nominal.runs, nominal.failed, nominal.faults, nominal.isolated,
            nominal.identified) == ("nominal", 2, 0, 2, 2, 1)
    assert (nominal.latency_median_s, nominal.latency_p90_s) == (30.0, 38.0)
    assert (nominal.false_alarms, nominal.windows) == (0, 20)
    assert (nominal.neighbour_false_alarms, nominal.neighbour_windows) == (1, 100)
    assert nominal.neighbour_false_alarm_bound == pytest.approx(false_alarm_bound(1, 100))
    assert (default.runs, default.failed, default.faults, default.isolated) == (2, 1, 1, 0)
    assert (default.false_alarms, default.windows, default.neighbour_windows) == (3, 50, 0)
    assert default.latency_median_s is None and default.worst and not nominal.worst
    counts = [(b.label, b.runs, b.failed, b.faults) for b in dims["observers.count"].bins]
    assert counts == [("2–3", 2, 0, 2), ("4–5", 1, 0, 1), ("6–7", 0, 0, 0), ("8", 1, 1, 0)]
    assert [b.worst for b in dims["observers.count"].bins] == [False, False, False, True]
    inspection, transfer = dims["fault.phase"].bins
    assert (inspection.runs, inspection.isolated, transfer.runs, transfer.isolated) == \
        (2, 2, 1, 0)
    assert transfer.worst and not inspection.worst  # none failed: fewest isolated


def test_the_report_has_a_table_per_dimension(campaign: Path) -> None:
    report = write_campaign_report(campaign, "t", IDS).read_text()
    assert "## By drawn dimension" in report
    for name in ("mission", "observers.count", "fault.phase"):
        assert f"\n### {name}\n" in report
    # 0 in 20 windows cannot show 1e-3; 1 in 100 is over it
    assert ("| nominal | 2 | 0 | 2 | 0 | 100% (2/2) | 50% (1/2) | 30 / 38 | 30 | 0.0000 (0/20; "
            "95% ≤ 0.14); too few windows to show the target: needs ≥ 2,995 windows (has 20) | "
            "0.0100 (1/100; 95% ≤ 0.047) |") in report
    assert ("| **default** (worst) | 2 | 1 | 1 | 0 | 0% (0/1) | 0% (0/1) | - / - | - | 0.0600 "
            "(3/50;") in report
    assert "| 6–7 | 0 | 0 | 0 | 0 | - | - | - / - | - | - | - |" in report
    saved = json.loads((campaign / "dimensions.json").read_text())
    assert saved["mission"]["domain"] == DOMAINS["mission"]
    assert [(b["bin"], b["runs"], b["failed"], b["worst"]) for b in saved["mission"]["bins"]] \
        == [("nominal", 2, 0, False), ("default", 2, 1, True)]


def test_a_campaign_that_draws_nothing_has_no_such_section(tmp_path: Path) -> None:
    _write(tmp_path, "a", {"injected_faults": [], "scores": _scores([], 0, 3)})
    assert "By drawn dimension" not in write_campaign_report(tmp_path, "t", ["a"]).read_text()
    assert not (tmp_path / "dimensions.json").exists()
