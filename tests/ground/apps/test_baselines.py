"""The baseline detectors' app (ground/apps/baselines.py): with the sequential test as the main
detector, the window test alone is a baseline too (``window``), its verdicts the FDIR's own
windows', declared after ``fdir.persistence`` failed ones; with the window test as the main
detector, there is no such baseline (it would be the main one again)."""

from __future__ import annotations

from ground.apps.baselines import BaselinesApp
from interfaces.contracts.messages import BaselineVerdict, FdirWindow
from tests.conftest import app_alone, small_scenario


def _window(sc: int, k: int, exceeded: bool | None) -> FdirWindow:
    """Observer ``sc``'s ``k``-th 30 s window, its H_m 0.2 against τ 0.1 when exceeded."""
    metric = None if exceeded is None else (0.2 if exceeded else 0.05)
    return FdirWindow(sender="ground", t_sim=30.0 * (k + 1), spacecraft=sc,
                      t_start_s=30.0 * k, t_end_s=30.0 * (k + 1), images=30, metric=metric,
                      threshold=0.1, exceeded=exceeded, dh=1.0, dh_pred=1.0)


def _window_verdicts(detector: str, persistence: int) -> list[BaselineVerdict]:
    scenario = small_scenario(fdir={"detector": detector, "persistence": persistence})
    app, sent = app_alone(BaselinesApp, scenario, node="ground", spacecraft=None)
    for k, exceeded in enumerate([False, None, True, True, True, False, True]):
        app.on_window(_window(1, k, exceeded))
    app.step(300.0)
    return [m for m in sent if isinstance(m, BaselineVerdict) and m.detector == "window"]


def test_the_window_test_is_a_baseline_beside_the_sequential_test() -> None:
    verdicts = _window_verdicts("sequential", 1)
    assert [v.exceeded for v in verdicts] == [False, None, True, True, True, False, True]
    assert [v.t_end_s for v in verdicts if v.alarm] == [90.0, 210.0]  # once per episode
    assert all(v.statistic == (None if v.exceeded is None else 0.2 if v.exceeded else 0.05)
               and v.threshold == 0.1 for v in verdicts)
    twice = _window_verdicts("sequential", 2)
    assert [v.t_end_s for v in twice if v.alarm] == [120.0]  # two failed in a row


def test_no_window_baseline_where_the_window_test_is_the_main_detector() -> None:
    assert _window_verdicts("window", 1) == []
