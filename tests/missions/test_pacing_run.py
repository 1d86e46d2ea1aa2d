"""``--realtime SPEED`` (sim/pacing.py) with a node slower than SPEED: as a ceiling the lockstep
holds (every tick answered, none late, the run slower than SPEED); with hard deadlines the slow
node misses ticks, counted as its own, and the status says how the run was paced.  A real sim
node and a real executive answering from its own thread, on the in-process transport."""

from __future__ import annotations

import logging
import threading
import time

import numpy as np
import pytest

from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import SimStatus
from interfaces.runtime.app import App, AppContext
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive, TickClient
from interfaces.runtime.transport import InprocNetwork
from sim.node import SimNode
from tests.conftest import small_scenario

STEP_S = 0.02
"""Wall time the slow node spends on every tick, s."""


class SlowApp(App):
    """A high-rate app that takes ``STEP_S`` of wall time per step."""

    NAME = "slow"
    RATE = "high"
    steps = 0

    def step(self, t: float) -> None:
        time.sleep(STEP_S)
        self.steps += 1


def _paced_run(hard: bool) -> tuple[SimNode, SlowApp, SimStatus, float]:
    sc = small_scenario("pace", duration_s=5.0, observers={"count": 1})  # 11 ticks of 0.5 s
    net = InprocNetwork()
    bus = Bus("sc1", "pace", net.endpoint())
    app = SlowApp(AppContext(bus=bus, scenario=sc, node="sc1", spacecraft=1,
                             rng=np.random.default_rng(0), log=logging.getLogger("t")))
    client = TickClient(Executive(bus, sc, [app]))
    stop = threading.Event()
    serving = threading.Thread(target=client.serve, args=(stop,), daemon=True)
    serving.start()
    statuses: list[SimStatus] = []
    Bus("ground", "pace", net.endpoint()).subscribe(cat.SIM_STATUS.key("pace"), SimStatus,
                                                   statuses.append, immediate=True)
    sim = SimNode(Bus("sim", "pace", net.endpoint()), sc, ["sc1"], realtime_speed=100.0,
                  hard_deadline=hard)
    wall0 = time.monotonic()
    try:
        assert sim.run()
    finally:
        stop.set()
        serving.join(timeout=5.0)
    return sim, app, statuses[-1], time.monotonic() - wall0


def test_as_a_ceiling_the_lockstep_holds_and_the_run_goes_slower() -> None:
    sim, app, status, wall = _paced_run(hard=False)
    n_ticks = sim.scenario.n_ticks
    assert sim.lockstep.missed_answers == 0 and sim.lockstep.late == {}
    assert app.steps == n_ticks  # every tick run, none skipped
    assert wall >= n_ticks * STEP_S  # the slow node set the pace, not the 100x ceiling
    assert status.state == "finished" and status.pace_ceiling == 100.0
    assert not status.hard_deadline and status.late_ticks == {}


def test_with_hard_deadlines_the_slow_node_misses_ticks_counted_as_its_own() -> None:
    sim, _, status, _ = _paced_run(hard=True)
    late = sim.lockstep.late.get("sc1", 0)
    assert late >= 1 and sim.lockstep.missed_answers == late  # 20 ms per 5 ms tick
    assert status.hard_deadline and status.late_ticks == {"sc1": late}


@pytest.mark.parametrize("speed", [0.0, -1.0, float("nan")])
def test_a_pace_that_is_not_a_positive_speed_is_refused(speed: float) -> None:
    sc = small_scenario("pace", observers={"count": 1})
    with pytest.raises(ValueError, match="positive speed"):
        SimNode(Bus("sim", "pace", InprocNetwork().endpoint()), sc, [], realtime_speed=speed)
