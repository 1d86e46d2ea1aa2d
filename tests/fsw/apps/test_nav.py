"""Physical sanity at the nav's boundary (fsw/apps/nav.py, issue 16): a value outside a
message's physical ranges is refused where it enters, counted, and never reaches the filter; a
filter that diverges anyway restarts from its next good measurement, says so in its telemetry,
and the ground sees it (the ranges themselves: tests/interfaces/contracts/test_messages.py)."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from fsw.apps.nav import NavApp
from ground.apps.telemetry import TelemetryMonitor
from interfaces.contracts import catalogue as cat
from interfaces.contracts import messages as m
from interfaces.contracts.messages import StateEstimate
from interfaces.runtime.app import AppContext
from interfaces.runtime.bus import Bus
from interfaces.runtime.transport import InprocNetwork
from tests.conftest import small_scenario
from tests.interfaces.contracts.test_messages import _relnav

MISSION = "phys"


def test_an_absurd_measurement_never_reaches_the_filter() -> None:
    """A schema-valid-looking relnav with r = 1e308 m, sent as bytes on sc1's sensor key: the
    nav's Bus drops and counts it, the filter goes on with the genuine measurements."""
    net = InprocNetwork()
    raw, bus = net.endpoint(), Bus("sc1", MISSION, net.endpoint())
    nav = NavApp(_ctx(bus))
    nav.wire()
    key = cat.RELNAV.key(MISSION, "sc1")
    good = _relnav([10.0, 0.0, 0.0])
    raw.publish(key, "RelNavMeasurement", good.model_copy(update={"seq": 1}).model_dump_json()
                .encode())
    bad = good.model_dump_json().replace("10.0", "1e308").replace('"seq":0', '"seq":2')
    raw.publish(key, "RelNavMeasurement", bad.encode())
    bus.dispatch(1.0)
    nav.step(1.0)
    assert bus.stats.invalid_dropped == 1
    assert nav.x is not None and np.isfinite(nav.x).all() and abs(nav.x[0] - 10.0) < 1e-9


def _ctx(bus: Bus) -> AppContext:
    sc = small_scenario(MISSION, rates={"high_hz": 10.0, "mid_hz": 1.0, "low_hz": 0.1},
                        observers={"count": 2})
    return AppContext(bus=bus, scenario=sc, node=bus.node, spacecraft=1,
                      rng=np.random.default_rng(0), log=logging.getLogger("test"))


def test_a_diverged_filter_restarts_and_the_ground_sees_it(
        caplog: pytest.LogCaptureFixture) -> None:
    nav = NavApp(_ctx(Bus("sc1", MISSION, InprocNetwork().endpoint())))
    sent: list[StateEstimate] = []
    nav.publish = lambda name, msg: sent.append(msg)  # type: ignore[method-assign,assignment]
    nav.on_relnav(_relnav([10.0, 0.0, 0.0], t=1.0))
    nav.step(1.0)
    assert len(sent) == 1 and sent[0].resets == 0
    nav.P[0, 0] = np.nan  # a numerical failure inside the filter
    nav.step(2.0)
    assert len(sent) == 1 and nav.resets == 1 and nav.x is None  # nothing published
    nav.step(3.0)
    assert len(sent) == 1  # no measurement yet: still nothing
    nav.on_relnav(_relnav([10.5, 0.0, 0.0], t=4.0))
    nav.step(4.0)
    assert len(sent) == 2 and sent[-1].resets == 1 and abs(sent[-1].x[0] - 10.5) < 1e-9
    assert np.allclose(np.diag(sent[-1].P)[:3], 0.1**2)  # restarted from the sensor's covariance

    ground = Bus("ground", MISSION, InprocNetwork().endpoint())
    monitor = TelemetryMonitor(_ctx(ground))
    status: list[m.TelemetryStatus] = []
    monitor.publish = lambda name, msg: status.append(msg)  # type: ignore[method-assign,assignment]
    for seq, est in enumerate(sent, start=1):
        monitor.on_tlm(est.model_copy(update={"seq": seq}))
    monitor.step(5.0)
    entry = next(e for e in status[-1].entries if e.spacecraft == 1)
    assert entry.nav_resets == 1
    assert any("navigation filter restarted" in r.message for r in caplog.records)
