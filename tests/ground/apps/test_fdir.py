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
    LinkCounter,
    LinkStats,
    Message,
    OnboardFdirEvent,
    PoiObservations,
    ProAssignment,
    ProAssignments,
    ProElements,
    StoreCounter,
    TransferPlanMsg,
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
    reports = [m for m in sent if isinstance(m, FaultReport) and m.spacecraft == 2]
    # 6 of 10 lost where the link loses none nominally: the first such window decides alone
    # (sc1, which sends nothing with its camera on, is a silent link: not this test's)
    assert [(r.spacecraft, r.fault_class, r.t_sim) for r in reports] == [(2, "link", 20.0)]
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
    reports = [(r.spacecraft, r.fault_class, r.t_sim) for r in sent
               if isinstance(r, FaultReport) and r.spacecraft == 2]
    # a lossless link never empties a window: the first silent one decides
    assert reports == ([] if camera_off else [(2, "link", 20.0)])
    windows = [m for m in sent if isinstance(m, FdirWindow) and m.spacecraft == 2]
    assert len(windows) == 4 and all(w.metric is None for w in windows)


def _passes_app() -> FdirApp:
    """The FDIR of two observers under one station's passes (29-498 s, then 5,963 s)."""
    sc = small_scenario("fp", duration_s=6400.0, target={"pois": 200},
                        rates={"fdi_period_s": 30.0},
                        observers={"count": 2},
                        orbit={"inclination_deg": 51.6, "raan_deg": 255.0,
                               "arg_latitude_deg": 90.0},
                        ground={"contact": "passes", "stations": [
                            {"name": "mid", "latitude_deg": 48.08, "longitude_deg": 11.28}]})
    bus = Bus("ground", "fp", InprocNetwork().endpoint())
    return FdirApp(AppContext(bus=bus, scenario=sc, node="ground", spacecraft=None,
                              rng=np.random.default_rng(0), log=logging.getLogger("t")))


def _assignment(aid: int, t_sim: float, t_depart: float) -> ProAssignments:
    pro = ProElements(rho_x_m=10.0 + aid, alpha_x_rad=0.0, rho_y_m=0.0, rho_z_m=15.0,
                      alpha_z_rad=0.0)
    return ProAssignments(sender="ground", seq=aid, t_sim=t_sim, assignments=[ProAssignment(
        spacecraft=1, assignment_id=aid, phase="p", pro=pro, t_depart_s=t_depart,
        t_arrive_s=t_depart + 600.0)])


def test_assignments_held_for_a_pass_leave_only_the_newest_in_force() -> None:
    """Sent out of contact, each waits for the pass at 5,963 s; the observer flies only the
    newest, so the older ones, superseded before they started, are no plan of the twin's."""
    pipeline = _passes_app().pipeline
    pipeline.assignments(_assignment(1, 10.0, 100.0))  # in contact: in force from 100 s
    pipeline.assignments(_assignment(2, 1000.0, 1100.0))  # held: from the next acquisition
    pipeline.assignments(_assignment(3, 2000.0, 2100.0))
    plans = pipeline.observers[1].plans
    assert sorted(plans) == [1, 3]
    assert plans[1].t_from_s == 100.0 and plans[3].t_from_s == pytest.approx(5963.0, abs=1.0)


def _plan_msg(aid: int, status: str, t_s: list[float]) -> TransferPlanMsg:
    x = [[10.0 + aid, 0.0, 15.0, 0.0, 0.0, 0.0]] * len(t_s)
    return TransferPlanMsg(sender="sc1", t_sim=t_s[0] if t_s else 0.0, spacecraft=1,
                           assignment_id=aid, t_s=t_s, x=x,
                           u_mps2=[[0.0, 0.0, 0.0]] * max(len(t_s) - 1, 0), dv_mps=0.0,
                           status=status, iterations=0, min_range_m=0.0, solve_ms=0.0)


@pytest.mark.parametrize("status", ["infeasible_thrust_limit", "refused"])
def test_an_assignment_the_observer_refused_is_no_plan_of_the_twins(status: str) -> None:
    """sc1 refused assignment 2 (no plan meets every constraint; a refusal with its coast
    nodes or with none): it keeps assignment 1, whose PRO its windows are judged against,
    and the ground's own copy of assignment 2, coming after, does not bring it back."""
    pipeline = _passes_app().pipeline
    pipeline.assignments(_assignment(1, 10.0, 100.0))
    pipeline.assignments(_assignment(2, 300.0, 400.0))
    obs = pipeline.observers[1]
    assert sorted(obs.plans) == [1, 2]
    pipeline.transfer(_plan_msg(2, status, [400.0, 700.0] if status != "refused" else []))
    pipeline.assignments(_assignment(2, 300.0, 400.0))
    assert sorted(obs.plans) == [1] and obs.refused == {2}
    assert obs.plan_at(800.0) is obs.plans[1]
    pipeline.transfer(_plan_msg(1, "solved", [100.0, 700.0]))  # a plan flown is the path
    assert obs.plans[1].transfer is not None and obs.plans[1].holds_from_s == 700.0


def test_an_observer_nothing_of_which_comes_down_in_a_pass_has_lost_its_link() -> None:
    """The pass acquired at 29 s: by 62 s (an FDI period and the FDIR's latency after it)
    sc1 has been heard and sc2 not: sc2's link fault is declared then, once; with nobody
    heard, nothing is."""
    pipeline = _passes_app().pipeline
    aos = pipeline.contact.windows[0][0]
    assert aos == pytest.approx(29.0, abs=1.0)
    quiet = pipeline.due(aos + 33.0)
    assert not [m for m in quiet if isinstance(m, FaultReport)]  # nobody heard yet
    pipeline.observations(_obs(1, aos + 1.0, 1, [1]))
    reports = [[(r.spacecraft, r.fault_class) for r in pipeline.due(t)
                if isinstance(r, FaultReport)] for t in (aos + 20.0, aos + 34.0, aos + 40.0)]
    assert reports == [[], [(2, "link")], []]
    late = _passes_app().pipeline  # out of contact (after the pass's LOS at 498 s): no
    late.observations(_obs(1, 600.0, 1, [1]))  # silence of a pass (its windows' are theirs)
    assert not [m for m in late.due(640.0)
                if isinstance(m, FaultReport) and m.window_end_s == 640.0]


def test_a_window_whose_reports_are_lost_or_aboard_is_not_judged_and_says_why() -> None:
    pipeline = _passes_app().pipeline
    obs = pipeline.observers
    obs[1].plans[1] = obs[2].plans[1] = FlightPlan(0.0, Pro(20.0, 0.0, 0.0, 25.0, 0.0))
    obs[1].overflow = [(40.0, 50.0)]  # sc1's store lost its reports of [30, 60)
    obs[2].aboard_since_s = 45.0  # sc2's reports from 45 s are still aboard
    out = [*pipeline.evaluate(0), *pipeline.evaluate(1)]
    windows = {(w.spacecraft, w.t_start_s): w for w in out if isinstance(w, FdirWindow)}
    assert windows[(1, 30.0)].unjudged == "store_overflow"
    assert windows[(2, 30.0)].unjudged == "aboard"
    assert windows[(2, 0.0)].unjudged == "no_images"  # before: nothing received, a silence
    assert all(w.exceeded is None for w in windows.values())
    reports = [r for r in out if isinstance(r, FaultReport)]
    # the silent first windows are a link fault each (a lossless link never empties one), the
    # lost reports one of known cause, and the reports aboard none
    assert [(r.spacecraft, r.cause) for r in reports] == [(1, None), (2, None),
                                                          (1, "store_overflow")]


def test_what_is_aboard_is_known_only_from_what_comes_down() -> None:
    """The store's accounting counts once its dump brought something down (a cut link tells
    the ground nothing), and only in the pass it came in."""
    pipeline = _passes_app().pipeline
    obs = pipeline.observers[1]

    def stats(t: float, dumped: int, since: float | None) -> LinkStats:
        store = StoreCounter(dumped=dumped, judged_since_s=since)
        return LinkStats(sender="ground", t_sim=t, node="ground", links=[
            LinkCounter(src="sc1", dst="ground", store=store)])

    pipeline.link_stats(stats(100.0, 0, 40.0))  # nothing came down: unknown
    assert obs.aboard_since_s is None
    pipeline.link_stats(stats(110.0, 5, 40.0))
    assert obs.aboard_since_s == 40.0 and obs.aboard_before(60.0)
    pipeline.due(6000.0)  # the next pass, in which nothing of sc1 came down
    assert obs.aboard_since_s is None and not obs.aboard_before(60.0)
