"""The nav's NIS test in the window test, in a real (in-process) run: a thruster leak is an
unmodelled force in the nav filter, so the window after its onset fails on the NIS before the
information metric or the Δv spent show it; the fault is declared unidentified on that window
and identified as an actuator fault on a later one, while the healthy observers' NIS stays
under its χ² quantile."""

from __future__ import annotations

import pytest

from deploy.inproc import run_inproc
from harness.summary.fdir import series_of
from interfaces.contracts.messages import FaultReport, FdirWindow
from tests.conftest import collector, small_scenario

ONSET_S = 50.0


@pytest.fixture(scope="module")
def run() -> tuple[list[FdirWindow], list[FaultReport]]:
    sc = small_scenario("nis", duration_s=180.0, target={"pois": 500},
                        rates={"fdi_period_s": 20.0}, fdir={"detector": "window"},
                        faults=[{"spacecraft": 1, "kind": "thruster_bias", "start_s": ONSET_S,
                                 "magnitude": 0.2}])
    tap, got = collector(FdirWindow, FaultReport)
    run_inproc(sc, tap=tap)
    return got["FdirWindow"], got["FaultReport"]


def test_the_leak_is_declared_on_its_nis_and_identified_after(
        run: tuple[list[FdirWindow], list[FaultReport]]) -> None:
    windows, reports = run
    judged = [w for w in windows if w.spacecraft == 1 and w.exceeded is not None]
    first = judged[0]
    assert first.t_start_s >= ONSET_S and first.exceeded and first.failed == ["nis"]
    assert first.nis_sum > first.nis_limit  # type: ignore[operator]
    mine = [(r.t_sim, r.fault_class) for r in reports if r.spacecraft == 1]
    assert mine[0] == (first.t_end_s, None)  # declared, its class waiting for the geometry
    assert mine[1][1] == "actuator" and mine[1][0] > first.t_end_s
    assert all(r.spacecraft == 1 for r in reports)


def test_healthy_observers_nis_within_its_quantile(
        run: tuple[list[FdirWindow], list[FaultReport]]) -> None:
    healthy = [w for w in run[0] if w.spacecraft != 1 and w.nis_sum is not None]
    assert len(healthy) >= 4
    assert all(w.nis_sum < w.nis_limit and not w.exceeded for w in healthy)  # type: ignore[operator]


def test_the_campaign_series_records_a_window_failed_on_its_nis(
        run: tuple[list[FdirWindow], list[FaultReport]]) -> None:
    """summary.json's ``fdir_series`` marks the leak's first window as failed on another test:
    its H_m is under τ, so a re-scoring from H_m alone would miss it."""
    first = next(w for w in run[0] if w.spacecraft == 1 and w.exceeded is not None)
    main = series_of(run[0], []).main
    row = next(r for r in main if r.spacecraft == 1 and r.t_start_s == first.t_start_s)
    assert row.statistic < row.threshold and row.other_tests_failed
    assert row.exceeded(scale=10.0) and row.model_dump()[5] == 1.0  # on disk: the sixth value
    healthy = [r for r in main if r.spacecraft != 1]
    assert healthy and not any(r.other_tests_failed for r in healthy)
