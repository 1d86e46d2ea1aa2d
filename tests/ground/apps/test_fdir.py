"""The FDIR app's handling of late and missing telemetry, driven message by message: a late
observation is fused into the ground's map (not judged, not dropped), a window without images
is no decision (never zero information gain), and observations missing by sequence number
make a link fault once the lost share stays above ``fdir.loss_tol``; an observer whose camera its
onboard FDIR turned off is not silent."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from gnc.pro import Pro
from gnc.twin import FlightPlan
from ground.apps.fdir import FdirApp
from interfaces.contracts.messages import (
    FaultReport,
    FdirWindow,
    Message,
    OnboardFdirEvent,
    PoiObservations,
)
from interfaces.runtime.app import AppContext
from interfaces.runtime.bus import Bus
from interfaces.runtime.transport import InprocNetwork
from tests.conftest import small_scenario


def _app() -> tuple[FdirApp, list[Message]]:
    sc = small_scenario("fa", target={"pois": 200}, rates={"fdi_period_s": 10.0},
                        observers={"count": 2}, fdir={"persistence": 2, "latency_s": 0.0})
    bus = Bus("ground", "fa", InprocNetwork().endpoint())
    app = FdirApp(AppContext(bus=bus, scenario=sc, node="ground", spacecraft=None,
                             rng=np.random.default_rng(0), log=logging.getLogger("t")))
    sent: list[Message] = []
    app.publish = lambda name, msg: sent.append(msg)  # type: ignore[method-assign]
    return app, sent


def _obs(sc: int, t: float, seq: int, poi: list[int]) -> PoiObservations:
    return PoiObservations(sender=f"sc{sc}", t_sim=t, seq=seq, spacecraft=sc, image_t_s=t,
                           poi=poi, precision=[0.01] * len(poi))


def test_late_observation_is_fused_not_judged() -> None:
    app, sent = _app()
    app.step(10.0)  # window [0, 10) judged: nothing received
    assert app.pipeline.window_start == 10.0
    before = app.pipeline.settled.F.copy()
    app.pipeline.observations(_obs(1, 5.0, 1, [3, 4]))  # image of the judged window, arriving late
    assert not app.pipeline.pending
    assert app.pipeline.settled.F[0, 3] == pytest.approx(before[0, 3] + 0.01)
    assert app.pipeline.settled.F[1, 3] == before[1, 3]
    windows = [m for m in sent if isinstance(m, FdirWindow)]
    assert len(windows) == 2 and all(w.metric is None and w.exceeded is None for w in windows)


def test_observations_missing_by_sequence_make_a_link_fault() -> None:
    app, sent = _app()
    seq = 0
    for k in range(4):  # four windows of 10 images each, 6 of them lost in windows 2 and 3
        for i in range(10):
            if k >= 1 and i < 6:
                seq += 1
                continue
            app.pipeline.observations(_obs(2, 10.0 * k + i, seq + 1, [1]))
            seq += 1
        app.step(10.0 * (k + 1))
    windows = [m for m in sent if isinstance(m, FdirWindow) and m.spacecraft == 2]
    assert [w.lost for w in windows] == [0, 6, 6, 6]
    reports = [m for m in sent if isinstance(m, FaultReport)]
    assert [(r.spacecraft, r.fault_class, r.t_sim) for r in reports] == [(2, "link", 30.0)]
    assert reports[0].metric == pytest.approx(0.6)
    assert app.pipeline.observers[2].lost_fraction() == pytest.approx(18 / 40)


@pytest.mark.parametrize("camera_off", [False, True])
def test_a_camera_turned_off_onboard_is_not_a_link_fault(camera_off: bool) -> None:
    app, sent = _app()
    app.pipeline.observers[2].plans[1] = FlightPlan(0.0, Pro(20.0, 0.0, 0.0, 25.0, 0.0), None,
                                                    None)
    if camera_off:  # its onboard FDIR acting on a camera declaration, as fsw/apps/fdir.py sends it
        app.pipeline.onboard(OnboardFdirEvent(sender="sc2", t_sim=12.0, spacecraft=2,
                                              event="sequence", name="camera_off",
                                              fault_class="camera", detail="camera_off"))
    for k in range(4):  # sc2 sends images in its first window only, then nothing
        if k == 0:
            for i in range(5):
                app.pipeline.observations(_obs(2, 2.0 * i, i + 1, [1]))
        app.step(10.0 * (k + 1))
    reports = [(r.spacecraft, r.fault_class, r.t_sim) for r in sent if isinstance(r, FaultReport)]
    assert reports == ([] if camera_off else [(2, "link", 30.0)])
    windows = [m for m in sent if isinstance(m, FdirWindow) and m.spacecraft == 2]
    assert len(windows) == 4 and all(w.metric is None for w in windows)
