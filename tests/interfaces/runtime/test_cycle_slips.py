"""Cycle slips (interfaces/runtime/executive.py): a rate group's run is judged on the CPU time
its apps took against its budget; its first run in a process is its start-up, logged and not
counted; every other overrun is a slip, logged with the app, the time and the duration."""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import pytest

from interfaces.contracts import topics
from interfaces.contracts.messages import Tick
from interfaces.contracts.scenario import Scenario
from interfaces.runtime import executive
from interfaces.runtime.app import App, AppContext
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive, GroupCount, judge_run
from interfaces.runtime.transport import InprocNetwork
from tests.conftest import small_scenario


class _CpuClock:
    """The thread's CPU clock, advanced by the apps below instead of by work (s)."""

    def __init__(self) -> None:
        self.now_s = 0.0

    def __call__(self) -> float:
        return self.now_s


class _Spend(App):
    """An app whose steps take the CPU times (ms) it is given, one per step."""

    NAME = "spend"
    RATE = "high"

    def __init__(self, ctx: AppContext, clock: _CpuClock, costs_ms: list[float]) -> None:
        super().__init__(ctx)
        self.clock, self.costs_ms = clock, list(costs_ms)

    def step(self, t: float) -> None:
        self.clock.now_s += self.costs_ms.pop(0) / 1e3


def _executive(scenario: Scenario, clock: _CpuClock, costs_ms: list[float]) -> Executive:
    bus = Bus("sc1", "m", InprocNetwork().endpoint())
    ctx = AppContext(bus=bus, scenario=scenario, node="sc1", spacecraft=1,
                     rng=np.random.default_rng(0), log=logging.getLogger("t"))
    return Executive(bus, scenario, [_Spend(ctx, clock, costs_ms)])


def _tick(k: int, scenario: Scenario) -> Tick:
    dt = scenario.rates.dt_s
    return Tick(sender=topics.SIM, t_sim=k * dt, k=k, dt_s=dt, expect={}, final=False)


def test_judge_run_leaves_the_first_run_out_and_counts_every_later_overrun() -> None:
    count = GroupCount(budget_ms=100.0)
    verdicts = [judge_run(count, ms, first) for ms, first in
                [(5000.0, True), (40.0, False), (100.0, False), (130.0, False), (20.0, False)]]
    assert verdicts == ["start-up", "within", "within", "slip", "within"]
    assert (count.runs, count.cycle_slips, count.max_exec_ms) == (4, 1, 130.0)
    assert judge_run(GroupCount(budget_ms=100.0), 50.0, True) == "within"


def test_a_slip_is_counted_on_cpu_time_and_logged_with_its_app_time_and_duration(
        monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    scenario = small_scenario("s")  # high group every 0.5 s: a 500 ms budget
    clock = _CpuClock()
    monkeypatch.setattr(executive.time, "thread_time", clock)
    ex = _executive(scenario, clock, [900.0, 20.0, 700.0, 30.0])
    with caplog.at_level(logging.WARNING, logger="insp.exec"):
        for k in range(4):
            ex.run_tick(_tick(k, scenario), barrier=False)
    high = ex.stats["high"]
    assert high.budget_ms == pytest.approx(500.0)
    assert (high.runs, high.cycle_slips, high.max_exec_ms) == (3, 1, pytest.approx(700.0))
    start_up, slip = (r.getMessage() for r in caplog.records)
    assert "high group took 900.0 ms of CPU" in start_up and "start-up" in start_up
    assert "t=0.000 s" in start_up
    assert "took 700.0 ms of CPU" in slip and "t=1.000 s" in slip
    assert "spend took 700.0 ms" in slip and "cycle slip #1" in slip


def test_a_restarted_process_starts_again(monkeypatch: pytest.MonkeyPatch) -> None:
    """The counters are restored; the new process's first run is its own start-up."""
    scenario = small_scenario("s")
    clock = _CpuClock()
    monkeypatch.setattr(executive.time, "thread_time", clock)
    before = _executive(scenario, clock, [10.0, 10.0])
    for k in range(2):
        before.run_tick(_tick(k, scenario), barrier=False)
    after = _executive(scenario, clock, [800.0, 800.0])
    after.restore(before.checkpoint())
    for k in range(2, 4):
        after.run_tick(_tick(k, scenario), barrier=False)
    high: Any = after.stats["high"]
    assert (high.runs, high.cycle_slips) == (2, 1)
