"""The campaign report on constructed run summaries: rates, latencies, false alarms, the
confusion matrix, magnitude bins and the ROC re-scored from the archived window series."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from harness.campaign.report import magnitude_bins, write_campaign_report
from harness.campaign.rescore import (
    SCALES,
    CampaignRun,
    alarms_at,
    detector_figures,
    fault_rows,
    load_runs,
    rescore,
    roc,
)
from harness.campaign.targets import target_figures
from harness.summary import MainWindow, RunSummary, SummaryError
from harness.summary.fdir import UnjudgedCounts


def _fault(sc: int, kind: str, start: float, detected: bool, latency: float | None,
           cls: str | None, expected: str) -> dict[str, object]:
    return {"spacecraft": sc, "kind": kind, "start_s": start, "detected": detected,
            "isolated": detected, "latency_s": latency, "identified_class": cls,
            "expected_class": expected, "identified_correctly": cls == expected,
            "declared_latency_s": latency}


def _scores(per_fault: list[dict[str, object]], false_alarms: int, nominal_cycles: int
            ) -> dict[str, object]:
    return {"per_fault": per_fault, "false_alarms": false_alarms,
            "nominal_cycles": nominal_cycles,
            "false_alarm_rate": false_alarms / nominal_cycles if nominal_cycles else None,
            "false_alarms_per_hour": None}


def _detection(sc: int, t: float, cls: str | None, metric: float | None = None,
               threshold: float | None = None) -> dict[str, object]:
    return {"spacecraft": sc, "time_s": t, "class": cls, "direction": None, "metric": metric,
            "threshold": threshold}


def _summary(rid: str, sections: dict[str, Any]) -> RunSummary:
    """A completed run's summary with ``sections`` (the rest as a run would have them)."""
    return RunSummary.model_validate({
        "scenario": rid, "seed": 1, "wall_s": 60.0, "status": "completed", "error": None,
        "detections": [], "fdir_settings": {"fdi_period_s": 100.0, "persistence": 2},
        **sections})


def _run(sections: dict[str, Any]) -> CampaignRun:
    return CampaignRun("r", "r", "unknown", _summary("r", sections))


def _write(out: Path, rid: str, summary: dict[str, Any], group: str | None = None) -> None:
    d = out / "runs" / rid
    d.mkdir(parents=True)
    if group is not None:  # as the campaign runner writes it beside the run
        (d / "campaign.json").write_text(json.dumps({"run": rid, "group": group}))
    _summary(rid, summary).write(d / "summary.json")


@pytest.fixture()
def campaign(tmp_path: Path) -> Path:
    # run a: camera fault on sc2 from 0 s, declared at 200 s (two windows over 0.05)
    _write(tmp_path, "a", {
        "injected_faults": [{"spacecraft": 2, "kind": "camera_degradation", "start_s": 0.0,
                             "end_s": None, "magnitude": 0.5}],
        "scores": _scores([_fault(2, "camera_degradation", 0.0, True, 200.0, "camera",
                                  "camera")], 0, 2),
        "baselines": {"cusum": _scores([_fault(2, "camera_degradation", 0.0, True, 100.0,
                                               None, "camera")], 0, 2)},
        "fdir_series": {"main": [[2, 0, 100, 0.5, 0.05], [2, 100, 200, 0.5, 0.05],
                                 [1, 0, 100, 0.01, 0.05], [1, 100, 200, 0.01, 0.05]]}},
           group="faulty")
    # run b: a thruster fault missed by the main detector, identified by nobody
    _write(tmp_path, "b", {
        "injected_faults": [{"spacecraft": 1, "kind": "thruster_bias", "start_s": 100.0,
                             "end_s": None, "magnitude": 0.3}],
        "scores": _scores([_fault(1, "thruster_bias", 100.0, False, None, None,
                                  "actuator")], 0, 0),
        "fdir_series": {"main": [[1, 100, 200, 0.03, 0.05], [1, 200, 300, 0.03, 0.05]]}},
           group="faulty")
    # run c: nominal, one false alarm (two windows just over the threshold)
    _write(tmp_path, "c", {
        "injected_faults": [],
        "scores": _scores([], 1, 2),
        "fdir_series": {"main": [[1, 0, 100, 0.06, 0.05], [1, 100, 200, 0.07, 0.05]]}})
    write_campaign_report(tmp_path, "t", ["a", "b", "c", "missing"])
    return tmp_path


def test_report_figures(campaign: Path) -> None:
    report = (campaign / "report.md").read_text()
    assert "3 of 4 runs finished (0 failed;" in report
    assert "Software: unknown (3 runs)." in report  # no version in these campaign.json
    assert "median 60 s, max 60 s, 0.05 worker-hours in all." in report
    assert "| main | 50% (1/2) | 50% (1/2) | 50% (1/2) | 200 / 200 / 200 | 0.2500 (1/4; 95% ≤ " \
        "0.75) |" in report
    assert "| cusum | 100% (1/1) | 100% (1/1) | - | 100 / 100 / 100 |" in report
    assert "| camera_degradation (→ camera) | 0 | 1 | 0 | 0 | 0 | 0 | 0 |" in report
    assert "| thruster_bias (→ actuator) | 0 | 0 | 0 | 0 | 0 | 0 | 1 |" in report
    # per campaign group: a and b form "faulty" (its nominal cycles are a's sc1); c, with no
    # campaign.json, is its own group by its id
    assert "| faulty | main | 50% (1/2) | 50% (1/2) | 50% (1/2) | 200 / 200 / 200 | " \
        "0.0000 (0/2; 95% ≤ 0.78) |" in report
    assert "| c | main | - | - | - | - / - / - | 0.5000 (1/2; 95% ≤ 0.97) |" in report
    # persistence re-scored: one window in a row declares run a's fault at 100 s, three never
    # do (it has two windows), and c's false alarm needs only two
    fa = "0.2500 (1/4; 95% ≤ 0.75) |"
    assert "| 1 of 1 | 50% (1/2) | 50% (1/2) | 100 / 100 / 100 | " + fa in report
    assert "| 2 of 2 (as run) | 50% (1/2) | 50% (1/2) | 200 / 200 / 200 | " + fa in report
    assert "| 3 of 3 | 0% (0/2) | 0% (0/2) | - / - / - | 0.0000 (0/4; 95% ≤ 0.53) |" in report
    # margins H_m/τ by the fault active in the window: a's sc1 and c's windows are nominal
    assert "| nominal | 4 | 0.7 | 1.39 | 1.4 | 50% (2/4) |" in report
    assert "| camera_degradation | 2 | 10 | 10 | 10 | 100% (2/2) |" in report
    assert "| thruster_bias | 2 | 0.6 | 0.6 | 0.6 | 0% (0/2) |" in report
    rows = list(csv.DictReader(open(campaign / "results.csv")))
    assert [r["group"] for r in rows] == ["faulty", "faulty", "faulty", "c"]
    assert [(r["run"], r["detector"], r["kind"]) for r in rows] == [
        ("a", "main", "camera_degradation"), ("a", "cusum", "camera_degradation"),
        ("b", "main", "thruster_bias"), ("c", "main", "none")]
    for png in ("roc.png", "confusion.png", "latency.png", "margins.png"):
        assert (campaign / png).stat().st_size > 5000


def test_roc_rescoring(campaign: Path) -> None:
    fa, det = roc(load_runs(campaign, ["a", "b", "c"]), "main")
    one = int(np.argmin(np.abs(SCALES - 1.0)))
    # at the configured threshold: the camera fault detected, the thruster fault missed; one
    # false alarm (run c) in 4 nominal windows (run a sc1, run c sc1)
    assert det[one] == pytest.approx(0.5) and fa[one] == pytest.approx(0.25)
    low = int(np.argmin(np.abs(SCALES - 0.5)))  # threshold 0.025: the 0.03 fault is caught,
    assert det[low] == pytest.approx(1.0)  # and the nominal sc1 of run a (0.01) still quiet
    assert fa[low] == pytest.approx(0.25)
    assert det[-1] == 0.0 and fa[-1] == 0.0  # threshold 0.5: nothing
    assert np.all(np.diff(det) <= 0)  # fewer detections as the threshold rises


def test_roc_scores_like_the_run(tmp_path: Path) -> None:
    """At scale 1 the ROC gives the run's own scores: a fault is detected by an alarm on any
    spacecraft while it is active (not only its own), and link or data-integrity
    declarations, which no threshold scales, count at every scale."""
    faults = [{"spacecraft": 2, "kind": "camera_degradation", "start_s": 0.0, "end_s": None,
               "magnitude": 0.5},
              {"spacecraft": 3, "kind": "link_loss", "start_s": 0.0, "end_s": 150.0,
               "magnitude": None}]
    run = _run({"injected_faults": faults, "detections": [_detection(3, 200.0, "link")],
                "fdir_series": {"main": [[1, 0, 100, 0.2, 0.05], [1, 100, 200, 0.2, 0.05],
                                         [2, 0, 100, 0.01, 0.05], [2, 100, 200, 0.01, 0.05]]}})
    fa, det = roc([run], "main")
    one = int(np.argmin(np.abs(SCALES - 1.0)))
    assert det[one] == 1.0  # sc1's alarm at 200 s falls in sc2's fault: detected
    assert fa[one] == 0.5  # ... and a false alarm on sc1, whose 2 windows are nominal
    # at 10x only the link declaration on sc3 remains: it detects the link fault, and, being
    # an alarm while sc2's fault is active, "detects" that one too (detection counts any
    # alarm; isolation, in the tables, needs the right spacecraft)
    assert det[-1] == 1.0 and fa[-1] == 0.0


def test_magnitude_bins() -> None:
    rows = [{"kind": "k", "magnitude": m, "run": str(i), "fault_index": 0}
            for i, m in enumerate([4.0, 5.5, 7.0, 8.5, 10.0, 13.0])]
    bins = magnitude_bins(rows)
    assert list(bins) == [("k", "4–7"), ("k", "7–10"), ("k", "10–13")]  # numeric order
    assert [len(v) for v in bins.values()] == [2, 2, 2]
    few = magnitude_bins(rows[:3])
    assert list(few) == [("k", "4"), ("k", "5.5"), ("k", "7")]


def test_m_of_n_persistence() -> None:
    """m exceedances among the last n windows declare once per episode; m == n is n in a row
    (threshold.Persistence)."""
    def series(levels: list[float]) -> list[MainWindow]:
        return [MainWindow(spacecraft=1, t_start_s=100.0 * i, t_end_s=100.0 * (i + 1),
                           statistic=h, threshold=0.05) for i, h in enumerate(levels)]

    gappy = series([0.1, 0.0, 0.1, 0.1, 0.1, 0.0, 0.0, 0.0, 0.1, 0.0, 0.1])
    assert [a.t_s for a in alarms_at(gappy, 1.0, 2, 2)] == [400.0]
    assert [a.t_s for a in alarms_at(gappy, 1.0, 2, 3)] == [300.0, 1100.0]
    assert [a.t_s for a in alarms_at(gappy, 1.0, 1, 1)] == [100.0, 300.0, 900.0, 1100.0]
    assert alarms_at(gappy, 3.0, 1, 1) == []  # threshold scaled above every level


def test_windows_failed_on_other_tests_count_at_every_threshold_scale() -> None:
    """A main-detector window failed by the plan, pointing, Δv or NIS test (sixth value 1) is
    exceeded whatever the information threshold's scale; a five-value row (a summary written
    before the flag) is judged on H_m alone."""
    rows = [[1, 0.0, 30.0, 0.001, 0.05, 1.0], [1, 30.0, 60.0, 0.001, 0.05, 0.0]]
    nis_only = [MainWindow.model_validate(r) for r in rows]
    assert [a.t_s for a in alarms_at(nis_only, 1.0, 1, 1)] == [30.0]
    assert [a.t_s for a in alarms_at(nis_only, 100.0, 1, 1)] == [30.0]
    assert alarms_at([MainWindow.model_validate(r[:5]) for r in rows], 1.0, 1, 1) == []


def test_the_report_says_when_summaries_lack_the_other_tests(tmp_path: Path) -> None:
    """Re-scoring from five-value rows undercounts the main detector: the report says so."""
    base = {"injected_faults": [], "duration_s": 60.0, "scores": _scores([], 0, 2)}
    _write(tmp_path, "old", base | {"fdir_series": {"main": [[1, 0, 30, 0.01, 0.05]]}})
    _write(tmp_path, "new", base | {"fdir_series": {"main": [[1, 0, 30, 0.01, 0.05, 0.0]]}})
    write_campaign_report(tmp_path, "x", ["old", "new"])
    assert "1 of 2 runs' summaries predate" in (tmp_path / "report.md").read_text()
    write_campaign_report(tmp_path, "x", ["new"])
    assert "predate" not in (tmp_path / "report.md").read_text()


def test_the_global_checks_declaration_counts_in_the_rescoring() -> None:
    """A common-mode fault (spacecraft 0) is isolated by the global check, which has no rows in
    ``fdir_series`` (hard campaign, late-common-mode-0000: H 0.33 against 0.031 at 3,300 s):
    the re-scoring keeps it while its statistic passes the scaled threshold."""
    run = _run({"injected_faults": [{"spacecraft": 0, "kind": "camera_calibration",
                                     "start_s": 3274.1, "magnitude": 0.6}],
                "fdir_settings": {"fdi_period_s": 30.0, "persistence": 1},
                "detections": [_detection(0, 3300.0, "common_mode", 0.33, 0.031)],
                "fdir_series": {"main": [[1, 3270.0, 3300.0, 0.01, 0.05, 0.0]]}})
    for scale, isolated in ((1.0, True), (10.0, True), (11.0, False)):
        (fault,) = rescore([run], "main", scale).per_fault
        assert fault.isolated is isolated, scale


def test_a_replays_main_detector_is_scored_over_its_faithful_span(tmp_path: Path) -> None:
    """A replay's declarations after its uplinks left the flown run's judge a trajectory nobody
    commanded: the report's main detector counts the faithful span's false alarms (0 here), the
    replay table's whole-run column the whole run's (2)."""
    whole, faithful = _scores([], 2, 10), _scores([], 0, 8)
    _write(tmp_path, "r", {"injected_faults": [], "duration_s": 100.0, "scores": whole,
                           "replay": {"settings": {"fdir.persistence": "1"}, "wall_s": 1.0,
                                      "faithful_until_s": 80.0, "matches_live": False,
                                      "scores_faithful": faithful},
                           "fdir_series": {"main": []}})
    write_campaign_report(tmp_path, "x", ["r"])
    main = [r for r in csv.DictReader(open(tmp_path / "results.csv"))
            if r["detector"] == "main"]
    assert [(r["false_alarms"], r["nominal_cycles"]) for r in main] == [("0", "8")]
    figures = detector_figures(tmp_path, ["r"])
    assert (figures["false_alarms"], figures["false_alarms_faithful"]) == (2, 0)


def test_faults_are_judged_from_the_first_window_that_could_judge_them(tmp_path: Path) -> None:
    """One pass, 0-300 s.  sc2's fault at 10 s, in the pass, before sc2's first judged window
    (150 s), declared at 180 s: 170 s from onset, 30 s from that window.  sc1's at 400 s,
    between passes, has no window after it but is declared (40 s, named 45 s; the neighbours
    30 s): judged from onset.  sc3's at 500 s, between passes, missed, with no window at
    all: no window could judge it, counted apart (the neighbours declared it at 50 s)."""
    passes = {"passes": [{"station": "s", "aos_s": 0.0, "los_s": 300.0, "duration_s": 300.0,
                          "tca_s": 150.0, "max_elevation_deg": 40.0}],
              "longest_gap_s": 700.0, "downlink_bps": 5e7, "store_bytes": 8 << 30,
              "stores": {}, "uplink_held": {}}
    faults = [_fault(2, "pointing_actuator", 10.0, True, 170.0, "actuator", "actuator"),
              {**_fault(1, "thruster_bias", 400.0, True, 40.0, "actuator", "actuator"),
               "identification_latency_s": 45.0},
              _fault(3, "camera_degradation", 500.0, False, None, None, "camera")]
    aboard = [_fault(2, "pointing_actuator", 10.0, False, None, None, "actuator"),
              _fault(1, "thruster_bias", 400.0, True, 30.0, None, "actuator"),
              _fault(3, "camera_degradation", 500.0, True, 50.0, None, "camera")]
    _write(tmp_path, "e", {
        "injected_faults": [{"spacecraft": f["spacecraft"], "kind": f["kind"],
                             "start_s": f["start_s"], "magnitude": 0.5} for f in faults],
        "scores": _scores(faults, 0, 4), "ground_contact": passes,
        "neighbours": {"agree": 2, "scores": _scores(aboard, 0, 4000),
                       "windows": {"neighbour_windows": 1, "judge_windows": 1,
                                   "nominal_judge_windows": 1, "nominal_exceeded": 0},
                       "disagreements": {"overruled": 0, "upheld": 0, "unruled": 0,
                                         "ground_only": 0}},
        "fdir_series": {"main": [[1, 60, 90, 0.01, 0.05], [2, 150, 180, 0.5, 0.05],
                                 [2, 180, 210, 0.5, 0.05]]}})
    rows = fault_rows(load_runs(tmp_path, ["e"]))
    main = [r for r in rows if r["detector"] == "main"]
    assert [(r["judgeable_s"], r["unjudged"], r["contact"]) for r in main] == [
        (150.0, False, "in_pass"), (400.0, False, "between_passes"),
        (None, True, "between_passes")]
    assert [r["window_latency_s"] for r in main] == [30.0, 40.0, None]
    assert [r["first_latency_s"] for r in main] == [170.0, 30.0, 50.0]
    figures = {f.name.split(" (")[0]: f for f in target_figures(rows, load_runs(tmp_path, ["e"]))}
    assert figures["faults"].value == "3 (1: 1 between passes)"
    assert figures["detected and isolated, of the judgeable"].value == "100% (2/2)"
    assert figures["detected and isolated, of the judgeable"].met is True
    assert figures["identified as actuator"].value == "100% (2/2)"
    assert "identified as camera" not in figures  # its only fault could not be judged
    assert figures["latency from the first judgeable window"].value == "35 / 39 / 40"
    onset = figures["latency from onset, the 1 faults after their observer's first judgeable "
                    "image, median / p90 / max"]
    assert (onset.value, onset.met) == ("40 / 40 / 40", False)  # sc1's: sc2's began before
    named = figures["actuator named, from onset"]
    assert (named.value, named.met) == ("45 / 45 / 45", False)  # median ≤ 30 s
    between = figures["between passes, neighbours on"]
    assert (between.value, between.met) == ("40 / 48 / 50", False)  # median ≤ 20 s
    assert figures["false alarms per nominal neighbour-window"].met is True  # 0/4000: ≤ 7.5e-4
    # 0/4: ≤ 0.53, and 4 windows cannot show 1e-3 even without a false alarm
    ground = figures["false alarms per nominal observer-window"]
    assert ground.met is None
    assert ground.note == "too few windows to show the target: needs ≥ 2,995 windows (has 4)"
    report = write_campaign_report(tmp_path, "x", ["e"]).read_text()
    assert "| detected and isolated, of the judgeable | 100% (2/2) | ≥ 98% | met |" in report
    assert f"95% bound ≤ 0.001 | {ground.note} |" in report
    assert "Settings:" not in report  # no campaign.json: nothing to say they were


def _passes(*spans: tuple[float, float]) -> dict[str, Any]:
    return {"passes": [{"station": "s", "aos_s": a, "los_s": b, "duration_s": b - a,
                        "tca_s": (a + b) / 2, "max_elevation_deg": 40.0} for a, b in spans],
            "longest_gap_s": 700.0, "downlink_bps": 5e7, "store_bytes": 8 << 30,
            "stores": {}, "uplink_held": {}}


@pytest.mark.parametrize("duration", [1400.0, 1350.0])
def test_a_link_fault_between_passes_is_judged_from_the_next_pass(duration: float) -> None:
    """Passes 0-300 s and 1,000-1,300 s, FDI windows of 100 s.  A link cut at 400 s, stamped
    at 500 s and declared at 1,350 s (the silence known once the pass is over): judgeable from
    the acquisition at 1,000 s, 350 s later; in a run that ends before that pass's end and a
    window (1,350 s), no window could judge it.  Never a latency below zero."""
    fault = {**_fault(2, "link_loss", 400.0, True, 100.0, "link", "link"),
             "declared_latency_s": 950.0}
    run = _run({"injected_faults": [{"spacecraft": 2, "kind": "link_loss", "start_s": 400.0}],
                "scores": _scores([fault], 0, 4), "ground_contact": _passes((0, 300),
                                                                           (1000, 1300)),
                "duration_s": duration, "fdir_series": {"main": [[2, 0, 100, 0.01, 0.05]]}})
    (row,) = [r for r in fault_rows([run]) if r["detector"] == "main"]
    assert row["contact"] == "between_passes"
    if duration == 1400.0:
        assert (row["judgeable_s"], row["window_latency_s"]) == (1000.0, 350.0)
    else:
        assert row["unjudged"] and row["window_latency_s"] is None


def test_data_integrity_is_unjudgeable_where_the_crosslinks_lose_too_much() -> None:
    """A faulty-data fault in a run whose crosslinks lose 15% (integrity_max_loss 10%: the
    check judged nothing) is not a miss; at 5% it is."""
    fault = _fault(1, "faulty_data", 100.0, False, None, None, "data_integrity")
    sections = {"injected_faults": [{"spacecraft": 1, "kind": "faulty_data", "start_s": 100.0,
                                     "magnitude": 2.0}],
                "scores": _scores([fault], 0, 4),
                "fdir_series": {"main": [[1, 100, 200, 0.01, 0.05]]}}
    for loss, unjudged in ((0.15, True), (0.05, False)):
        run = CampaignRun("r", "r", "-", _summary("r", sections), {"comms.packet_loss": loss})
        (row,) = [r for r in fault_rows([run]) if r["detector"] == "main"]
        assert row["unjudged"] is unjudged, loss
    census = SimpleNamespace(integrity_unjudged=UnjudgedCounts(crosslink_loss=3))
    run = CampaignRun("r", "r", "-", _summary("r", sections).model_copy(
        update={"fdir_thresholds": census}))  # its census: the check's reason, not drawn
    assert [r["unjudged"] for r in fault_rows([run]) if r["detector"] == "main"] == [True]


def test_a_fault_gone_before_its_observers_next_window_could_not_be_judged() -> None:
    """A fault on from 150 s to 160 s, its observer's windows 0-100 s and 400-500 s (none
    came down between): no window while it was on (or a window after)."""
    fault = _fault(1, "pointing_actuator", 150.0, False, None, None, "actuator")
    run = _run({"injected_faults": [{"spacecraft": 1, "kind": "pointing_actuator",
                                     "start_s": 150.0, "end_s": 160.0, "magnitude": 3.0}],
                "scores": _scores([fault], 0, 4),
                "fdir_series": {"main": [[1, 0, 100, 0.01, 0.05], [1, 400, 500, 0.01, 0.05]]}})
    assert [r["unjudged"] for r in fault_rows([run]) if r["detector"] == "main"] == [True]


def test_a_malformed_summary_is_refused_naming_its_file_and_field(tmp_path: Path) -> None:
    """A summary that is not one stops the report with pydantic's account of the field at
    fault, and the file it is in, rather than a KeyError deep in a figure."""
    _write(tmp_path, "ok", {"injected_faults": [], "scores": _scores([], 0, 1)})
    bad = tmp_path / "runs" / "bad"
    bad.mkdir()
    text = (tmp_path / "runs" / "ok" / "summary.json").read_text()
    (bad / "summary.json").write_text(text.replace('"nominal_cycles": 1', '"nominal_cycles": -1'))
    with pytest.raises(SummaryError, match=r"runs/bad/summary\.json: .*scores\.nominal_cycles "
                                           r"= -1: should be greater than or equal to 0"):
        write_campaign_report(tmp_path, "x", ["ok", "bad"])
