"""A baseline's alarm is logged as a baseline's (ground/apps/baselines.py): at INFO, saying
what it would declare, never with the FDIR's WARNING "fault declared" wording."""

from __future__ import annotations

import logging

import pytest

from ground.apps.baselines import BaselinesApp
from interfaces.contracts.messages import BaselineVerdict, FdirWindow
from tests.conftest import app_alone, small_scenario


def test_a_baselines_alarm_is_logged_as_a_baseline_at_info(
        caplog: pytest.LogCaptureFixture) -> None:
    scenario = small_scenario(fdir={"detector": "sequential", "persistence": 1})
    app, sent = app_alone(BaselinesApp, scenario, node="ground", spacecraft=None)
    app.on_window(FdirWindow(sender="ground", t_sim=30.0, spacecraft=2, t_start_s=0.0,
                             t_end_s=30.0, images=30, metric=0.9, threshold=0.1, exceeded=True,
                             dh=0.1, dh_pred=1.0))
    with caplog.at_level(logging.DEBUG, logger="t"):
        app.step(30.0)
    alarms = sorted(m.detector for m in sent if isinstance(m, BaselineVerdict) and m.alarm)
    assert {"fixed_threshold", "window"} <= set(alarms)  # H_m 0.9 over both levels
    said = [r for r in caplog.records if "baseline" in r.getMessage()]
    assert sorted(r.getMessage().split()[1] for r in said) == alarms
    for r in said:
        assert r.levelno == logging.INFO
        assert r.getMessage().startswith(f"baseline {r.getMessage().split()[1]} would declare "
                                         "sc2 at 30 s (a baseline")
        assert "fault declared" not in r.getMessage()
