"""summary.json's type (harness/summary): a real run's summary reads back as
written, byte for byte; its window series stay positional arrays on disk; a summary written
before a field existed loads with the field filled in and named, and writes back unchanged;
a malformed one is refused naming the field."""

from __future__ import annotations

import copy
import functools
import json
import operator
from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from harness.summary import (
    OTHER_TESTS_FLAG,
    RunSummary,
    SeriesWindow,
    SummaryError,
    ThresholdCensus,
)
from tests.conftest import recorded_run, small_scenario

OLDER = {OTHER_TESTS_FLAG, "fdir_thresholds.failed.nis",
         "scores.per_fault[].identification_latency_s", "detections[].evidence",
         "exec.ground.refused", "sim.participants"}
"""What the summaries of older versions lack (git history of harness/summary/build.py)."""


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, RunSummary]:
    """A short run with a thruster leak on sc1: its windows fail the NIS test (the sixth
    value 1.0) while the others' pass (0.0); the fault is declared and identified."""
    sc = small_scenario("rs", duration_s=200.0, target={"pois": 500},
                        rates={"fdi_period_s": 20.0},
                        faults=[{"spacecraft": 1, "kind": "thruster_bias", "start_s": 50.0,
                                 "magnitude": 0.2}])
    out = tmp_path_factory.mktemp("summary")
    _, summary = recorded_run(sc, out)
    return out / "summary.json", summary


def test_a_runs_summary_reads_back_as_written(run: tuple[Path, RunSummary]) -> None:
    path, written = run
    text = path.read_text()
    again = RunSummary.read(path)
    assert again.to_json() + "\n" == text  # load -> dump is the file, key order and floats
    assert again == written and again.filled == []
    assert list(json.loads(text))[:8] == ["scenario", "seed", "transport", "duration_s",
                                          "wall_s", "status", "error", "injected_faults"]
    assert again.scores is not None and again.detections
    (fault,) = again.scores.per_fault
    assert fault.isolated and fault.identified_class == "actuator"
    assert again.detections[0].fault_class is None  # "class": null, declared before identified
    assert '"class": null' in text and "fault_class" not in text


def test_window_series_are_named_in_memory_and_positional_on_disk(
        run: tuple[Path, RunSummary]) -> None:
    path, summary = run
    on_disk = json.loads(path.read_text())["fdir_series"]
    assert summary.fdir_series is not None
    assert list(on_disk) == summary.fdir_series.detectors() == [
        "main", "chi2_nis", "cusum", "fixed_threshold", "window"]
    main = summary.fdir_series.main
    assert [len(r) for r in on_disk["main"]] == [6] * len(main) and len(main) >= 10
    for row, w in zip(on_disk["main"], main, strict=True):
        assert row == [w.spacecraft, w.t_start_s, w.t_end_s, w.statistic, w.threshold,
                       1.0 if w.other_tests_failed else 0.0]
        assert type(row[0]) is int and type(row[5]) is float
    leak = [w for w in main if w.spacecraft == 1]
    assert leak and all(w.other_tests_failed and w.exceeded(scale=100.0) for w in leak)
    assert not any(w.other_tests_failed for w in main if w.spacecraft != 1)
    cusum = summary.fdir_series.of("cusum")
    assert cusum and all(len(r) == 5 for r in on_disk["cusum"])
    assert [SeriesWindow.model_validate(r) for r in on_disk["cusum"]] == list(cusum)


def _older(text: str) -> str:
    """The summary as older versions wrote it: five values a main-detector row, no NIS test,
    no identification latency, no evidence, no refusals counted, no lost participants."""
    d = json.loads(text)
    d["fdir_series"]["main"] = [r[:5] for r in d["fdir_series"]["main"]]
    del d["fdir_thresholds"]["failed"]["nis"]
    for f in d["scores"]["per_fault"]:
        del f["identification_latency_s"]
    for det in d["detections"]:
        del det["evidence"]
    for e in d["exec"].values():
        del e["refused"]
    del d["sim"]["participants"]
    return json.dumps(d, indent=2) + "\n"


def test_an_older_summary_loads_with_what_it_lacks_filled_and_named(
        run: tuple[Path, RunSummary], tmp_path: Path) -> None:
    path, _ = run
    old = tmp_path / "summary.json"
    old.write_text(_older(path.read_text()))
    s = RunSummary.read(old)
    assert OLDER <= set(s.filled) and OTHER_TESTS_FLAG in s.filled
    assert all(p.startswith(tuple(o.split(".")[0] for o in OLDER)) for p in s.filled)
    assert s.fdir_series is not None and s.fdir_thresholds is not None and s.scores
    assert not any(w.other_tests_failed for w in s.fdir_series.main)  # filled: False
    assert not any(w.exceeded(scale=100.0) for w in s.fdir_series.main)  # H_m alone
    assert s.fdir_thresholds.failed.nis == 0
    assert s.scores.per_fault[0].identification_latency_s is None
    assert s.sim is not None and s.sim.participants == {}
    assert s.to_json() + "\n" == old.read_text()  # written back as it was: nothing invented


def test_a_malformed_summary_is_refused_naming_the_field(run: tuple[Path, RunSummary]) -> None:
    path, _ = run
    good = json.loads(path.read_text())

    def error(change: Any) -> str:
        bad = copy.deepcopy(good)
        change(bad)
        with pytest.raises(ValidationError) as e:
            RunSummary.model_validate_json(json.dumps(bad))
        return str(e.value)

    msg = error(lambda d: d["fdir_series"]["main"].append([1, 0.0, 20.0]))
    assert f"fdir_series.main.{len(good['fdir_series']['main'])}" in msg
    assert "a row of 5 or 6 values (spacecraft, t_start_s, t_end_s, statistic, threshold, " \
           "other_tests_failed) expected, got 3" in msg
    msg = error(lambda d: d["fdir_series"]["main"][0].__setitem__(5, 0.5))
    assert "fdir_series.main.0.other_tests_failed" in msg and "valid boolean" in msg
    assert "scores.per_fault.0.latency_s" in error(
        lambda d: d["scores"]["per_fault"][0].update(latency_s="soon"))
    assert "status" in error(lambda d: d.update(status="finished"))
    assert "fdir_thresholds.failed.plans" in error(
        lambda d: d["fdir_thresholds"]["failed"].update(plans=1))  # unknown: refused
    assert "detections.0.class" in error(lambda d: d["detections"][0].update({"class": "x"}))


def test_reading_a_malformed_file_names_the_file(run: tuple[Path, RunSummary],
                                                 tmp_path: Path) -> None:
    path, _ = run
    bad = tmp_path / "summary.json"
    bad.write_text(path.read_text().replace('"seed": 3', '"seed": "three"'))
    with pytest.raises(SummaryError, match=rf"^{bad}: not a valid summary\.json: seed = 'three': "
                                           r"should be a valid integer"):
        RunSummary.read(bad)


def test_threshold_censuses_add_up_field_by_field(run: tuple[Path, RunSummary]) -> None:
    _, summary = run
    c = summary.fdir_thresholds
    assert c is not None and c.nominal_windows > 0
    total = functools.reduce(operator.add, [c, c, c])
    assert isinstance(total, ThresholdCensus)
    assert total.nominal_windows == 3 * c.nominal_windows
    assert total.threshold_by.model == 3 * c.threshold_by.model
    assert total.model_z.windows == 3 * c.model_z.windows


def test_the_disk_estimate_bounds_the_archive_a_run_writes(run: tuple[Path, RunSummary]
                                                           ) -> None:
    """The launcher's disk check (deploy/disk_space.py) is an upper estimate of the archive,
    and not a loose one: a run writes between half of it and all of it."""
    from deploy.disk_space import estimate_archive_bytes

    path, _ = run
    sc = small_scenario("rs", duration_s=200.0, target={"pois": 500},
                        rates={"fdi_period_s": 20.0})
    written = (path.parent / "run.mcap").stat().st_size
    assert 0.5 < written / estimate_archive_bytes(sc) <= 1.0
