"""Physical sanity at the boundary (issue 16): every message states the physical ranges of its
fields and a value outside is refused where it enters, counted, and never reaches a filter; a
navigation filter that diverges anyway restarts from its next good measurement, says so in its
telemetry, and the ground sees it."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from pydantic import ValidationError

from fsw.apps.nav import NavApp
from ground.apps.telemetry import TelemetryMonitor
from interfaces.contracts import catalogue as cat
from interfaces.contracts import messages as m
from interfaces.contracts.messages import (
    AttitudeEstimate,
    RelNavMeasurement,
    StateEstimate,
    ThrustCommand,
    TruthState,
    WheelCommand,
)
from interfaces.runtime.app import AppContext
from interfaces.runtime.bus import Bus
from interfaces.runtime.transport import InprocNetwork
from tests.conftest import small_scenario

MISSION = "phys"


def _relnav(r: list[float], t: float = 1.0, sigma_r: float = 0.1) -> RelNavMeasurement:
    return RelNavMeasurement(sender="sim", t_sim=t, spacecraft=1, r_m=r, v_mps=[0.0, 0.01, 0.0],
                             sigma_r_m=sigma_r, sigma_v_mps=0.001)


@pytest.mark.parametrize("build", [
    lambda: _relnav([1e308, 0.0, 0.0]),
    lambda: _relnav([m.MAX_RANGE_M * 1.01, 0.0, 0.0]),
    lambda: _relnav([10.0, 0.0, 0.0], sigma_r=1e9),
    lambda: _relnav([10.0, 0.0, 0.0], t=1e12),
    lambda: ThrustCommand(sender="sc1", t_sim=0.0, spacecraft=1, force_body_n=[11.0, 0, 0],
                          duration_s=1.0),
    lambda: WheelCommand(sender="sc1", t_sim=0.0, spacecraft=1, torque_body_nm=[0, 2.0, 0]),
    lambda: StateEstimate(sender="sc1", t_sim=0.0, spacecraft=1, x=[0, 0, 0, 0, 2e3, 0],
                          P=np.eye(6).tolist()),
    lambda: StateEstimate(sender="sc1", t_sim=0.0, spacecraft=1, x=[0.0] * 6,
                          P=(1e11 * np.eye(6)).tolist()),
    lambda: TruthState(sender="sim", t_sim=0.0, spacecraft=[1], r_lvlh_m=[[0, 0, 0]],
                       v_lvlh_mps=[[0, 0, 0]], w_body_radps=[[0, 50.0, 0]]),
    lambda: AttitudeEstimate(sender="sc1", t_sim=0.0, spacecraft=1, q_eci_body=[0, 0, 0, 1],
                             q_lvlh_body=[0, 0, 2, 1], gyro_bias_radps=[0, 0, 0],
                             sigma_att_rad=1e-4, target_lvlh_m=[0, 0, 0],
                             pointing_error_rad=0.0, mode="track", torque_body_nm=[0, 0, 0]),
], ids=["r 1e308", "r beyond range", "sigma 1e9 m", "t 1e12 s", "force 11 N", "torque 2 Nm",
        "velocity 2 km/s", "variance 1e11", "rate 50 rad/s", "quaternion component 2"])
def test_out_of_range_values_are_refused_by_the_schema(build) -> None:  # noqa: ANN001
    with pytest.raises(ValidationError):
        build()


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
