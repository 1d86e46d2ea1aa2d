"""The run report (harness/report.py) on summaries built here: it opens on the verdict and
the settings; the declarations table names each declaring test with its own statistic and
threshold; and with 64 observers its per-observer plots and tables stay short (the observers
with a fault or a declaration shown, the rest summed up)."""

from __future__ import annotations

from pathlib import Path

from PIL import Image

from harness.report import _exec_section, _identification_rows, _links_section, write_report
from harness.report_fdir_plot import plot_fdir
from harness.report_scale import ROWS_MOST, SHOWN_MOST, shown_observers
from harness.summary import Detection, ExecRecord, RunSummary
from harness.summary.scoring import Alarm, score
from interfaces.contracts.messages import FdirWindow, LinkCounter
from interfaces.contracts.scenario import Fault
from tests.conftest import small_scenario

FAULT = Fault(spacecraft=5, kind="camera_degradation", start_s=100.0, magnitude=0.5)


def _detection(sc: int, t: float, cls: str | None, **kw: object) -> Detection:
    return Detection.model_validate({"spacecraft": sc, "time_s": t, "class": cls,
                                     "direction": None, **kw})


def _summary(observers: int) -> RunSummary:
    """A run of ``observers`` observers: sc5's camera fault declared by the NIS scan, one
    false alarm on the last observer."""
    found = [_detection(5, 104.0, None, detector="sequential", test="nis_scan", metric=2.5,
                        threshold=1.5, evidence={"z": 9.0, "span": 4.0, "nis_scan": 1.0}),
             _detection(observers, 300.0, "actuator", test="information", metric=0.2,
                        threshold=0.1)]
    summary = RunSummary(scenario="t", seed=3, status="completed", error=None,
                         injected_faults=[FAULT], transport="inproc", wall_s=2.0)
    summary.detections = found
    summary.scores = score([FAULT], [Alarm(d.spacecraft, d.time_s, d.fault_class)
                                     for d in found], [], grace_s=10.0)
    return summary


def test_the_report_opens_on_the_verdict_then_the_settings(tmp_path: Path) -> None:
    _summary(6).write(tmp_path / "summary.json")
    text = write_report(tmp_path, small_scenario("t"),
                        settings={"scenario file": "s.toml", "--seed": "3"}).read_text()
    sections = [ln for ln in text.splitlines() if ln.startswith("## ")]
    assert sections[:3] == ["## Verdict", "## Settings", "## Run"]
    verdict = text.split("## Verdict", 1)[1].split("##", 1)[0]
    assert "1 of 1 faults declared: sc5 at t=104.0 s (+4.0 s, NIS scan (sequential)" in verdict
    assert "1 false alarm in 0 nominal windows: sc6 actuator at t=300.0 s" in verdict
    settings = text.split("## Settings", 1)[1].split("##", 1)[0]
    for row in ("| scenario file | s.toml |", "| --seed | 3 |", "| seed | 3 |",
                "| FDIR detector | sequential |"):
        assert row in settings


def test_the_declarations_table_names_the_declaring_test_and_its_figures() -> None:
    rows = _identification_rows(_summary(6))
    assert rows[0].split(" | ")[3:6] == ["declaring test", "statistic", "threshold"]
    assert rows[2].startswith("| 104 | 5 | unidentified | NIS scan (sequential) | "
                              "mean NIS per dof 2.5 | limit 1.5 |")
    assert rows[3].startswith("| 300 | 6 | actuator | information test (Eq. 9) | H_m,i 0.2 | "
                              "τ_i 0.1 |")


def _windows(observers: int) -> list[FdirWindow]:
    return [FdirWindow(sender="ground", t_sim=t + 30.0, spacecraft=sc, t_start_s=t,
                       t_end_s=t + 30.0, images=10, metric=0.01 * sc, threshold=0.1)
            for sc in range(1, observers + 1) for t in (0.0, 30.0, 60.0)]


def test_64_observers_give_a_short_report_and_capped_plots(tmp_path: Path) -> None:
    summary = _summary(64)
    shown = shown_observers(range(1, 65), summary)
    assert len(shown) == SHOWN_MOST and {5, 64} <= set(shown)  # the fault's, the alarm's
    summary.links = [LinkCounter(src=f"sc{a}", dst=f"sc{b}", sent=10, delivered=10 - (a == 7),
                                 dropped_loss=int(a == 7))
                     for a in range(1, 65) for b in range(1, 65) if a != b]
    summary.exec = {f"sc{n}": ExecRecord(cycle_slips={"high": int(n == 9)}, max_exec_ms={},
                                         app_errors=0, invalid_dropped=0, barrier_timeouts=0)
                    for n in range(1, 65)}
    links, execs = _links_section(summary), _exec_section(summary)
    assert len(links) == 4 + ROWS_MOST + 3  # heads, rows, a line for the rest
    assert sum(ln.startswith("| sc") for ln in execs) == ROWS_MOST
    assert f"{64 - ROWS_MOST} more nodes with less to show are in summary.json." in execs
    assert sum(ln.startswith("| sc7 → ") for ln in links) == ROWS_MOST  # those that dropped
    assert links[-2].startswith(f"{64 * 63 - ROWS_MOST} more links")
    assert any(ln.startswith("| sc9 | 1/0/0 |") for ln in execs)  # the one that slipped
    plot_fdir(tmp_path, _windows(64), shown, summary)
    width, height = Image.open(tmp_path / "fdir.png").size
    assert height <= 110 * (1.8 * SHOWN_MOST + 1)  # capped, not 64 panels
