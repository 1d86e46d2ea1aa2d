"""The FDIR pipeline's stages on constructed windows, without a bus: the link checks (loss by
sequence number against the link's limit, silence once per episode), the window context
(tracking and plan coverage decide which images are judged), the global check (a ratio every
observer shares is common mode, declared once), the declaration (persistence, a common mode is
not the observer's, a class found on a later window) and the data-integrity check (a report
off the ground's recomputation)."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from gnc.hardware_threshold import RatioModel
from gnc.image_scan import Crossing
from gnc.poi_map import PoiMap
from gnc.pro import Pro
from gnc.sequential_test import ScanResult
from gnc.twin import FlightPlan
from ground.fdir.constellation import ConstellationVerdict
from ground.fdir.declaration import Declarer
from ground.fdir.fused_views import FusedViews
from ground.fdir.global_check import GlobalCheck
from ground.fdir.identify import Evidence
from ground.fdir.information import Judgement
from ground.fdir.integrity import IntegrityCheck
from ground.fdir.link_checks import LinkChecks
from ground.fdir.observer import ObserverState
from ground.fdir.threshold import WindowThreshold
from ground.fdir.window import SettledMap, window_context
from interfaces.contracts.messages import (
    ConstellationWindow,
    FaultReport,
    FdirWindow,
    InfoCostTelemetry,
    PoiObservations,
    StoreCounter,
)
from tests.conftest import small_scenario

LOG = logging.getLogger("test")


def _obs(sc: int, t: float, seq: int) -> PoiObservations:
    return PoiObservations(sender=f"sc{sc}", t_sim=t, seq=seq, spacecraft=sc, image_t_s=t,
                           poi=[1, 2], precision=[0.01, 0.02])


BURSTY = {"packet_loss": 0.3, "burst": {"mean_length_packets": 50.0}}
"""A link whose healthy loss can empty a window: 30% in bursts of 50 packets."""


def test_silence_is_a_link_fault_once_per_episode() -> None:
    """On a bursty link one silent window is no proof (a healthy one empties a window of 30
    images with probability 0.3^(30/99) = 0.69): ``silent_windows`` of them are."""
    links = LinkChecks(small_scenario(comms=BURSTY, fdir={"silent_windows": 2}), "ground", LOG)
    assert links.images_per_window == 30 and not links.decisive(30, 30)
    obs = ObserverState()
    reports = [links.judge(1, obs, [], True, b)[1] for b in (10.0, 20.0, 30.0)]
    assert [len(r) for r in reports] == [0, 1, 0]
    assert reports[1][0].fault_class == "link" and reports[1][0].t_sim == 20.0
    assert links.judge(1, obs, [_obs(1, 31.0, 1)], True, 40.0) == (0, [])  # speaks again
    assert obs.silent == 0 and not obs.link_declared
    assert [len(links.judge(1, obs, [], True, b)[1]) for b in (50.0, 60.0)] == [0, 1]
    assert links.judge(2, ObserverState(), [], False, 10.0) == (0, [])  # camera off: none


@pytest.mark.parametrize("loss", [0.0, 0.15])
def test_one_silent_window_decides_when_a_healthy_link_could_hardly_empty_it(loss: float
                                                                          ) -> None:
    """No image of the 30 a window holds at a nominal loss of 0 or 15% (0.15^30 = 2e-25,
    against the window's share 8e-5): a link fault on the first silent window, once."""
    links = LinkChecks(small_scenario(comms={"packet_loss": loss},
                                      fdir={"silent_windows": 3}), "ground", LOG)
    assert links.decisive(30, 30)
    obs = ObserverState()
    reports = [links.judge(1, obs, [], True, b)[1] for b in (30.0, 60.0, 90.0)]
    assert [len(r) for r in reports] == [1, 0, 0]
    assert reports[0][0].fault_class == "link" and reports[0][0].window_end_s == 30.0


def _windows(links: LinkChecks, obs: ObserverState, images: dict[float, list[float]],
             reachable: bool = True, sent: dict[float, float] | None = None
             ) -> list[list[FaultReport]]:
    """Judge one observer's windows, each ending at a key with images at the times listed (its
    sequence numbers in order: nothing lost on the link), each sent at its time or later
    (``sent``: image time -> the message's time)."""
    seq = obs.last_seq
    out = []
    for b, times in images.items():
        mine = [_obs(1, t, seq := seq + 1).model_copy(update={"t_sim": (sent or {}).get(t, t)})
                for t in times]
        out.append(links.judge(1, obs, mine, True, b, reachable)[1])
    return out


def test_a_silence_straddling_two_windows_is_a_link_fault_when_images_resume() -> None:
    """A host's link cut for 30 s (docs/hosts.md): the observer's last image sent at 600 s, the
    next at 631 s (it rejoined at 630.1 s and sent the images of 628-630 s it recovered, late:
    judged in the window ending at 630 s).  No window is silent; 31 s without an image sent, a
    window's time, are a link fault (as one silent window would be on this link), declared with
    the window the images resume in.  20 s are not; on a bursty link, 60 s would be needed."""
    links = LinkChecks(small_scenario(comms={"packet_loss": 0.1}), "ground", LOG)
    cut = {600.0: [float(t) for t in range(570, 600)], 630.0: [600.0, 628.0, 629.0],
           660.0: [float(t) for t in range(630, 660)]}
    late = {628.0: 631.0, 629.0: 631.0, 630.0: 631.0}
    reports = _windows(links, ObserverState(), cut, sent=late)
    assert [len(r) for r in reports] == [0, 1, 0]
    declared = reports[1][0]
    assert (declared.fault_class, declared.window_end_s) == ("link", 630.0)
    assert (declared.metric, declared.threshold) == (31.0, 30.0)
    assert _windows(links, ObserverState(), cut) == [[], [], []]  # sent in time: 27 s
    short = {630.0: [float(t) for t in range(600, 616)], 660.0: [float(t) for t in range(636, 660)]}
    assert _windows(links, ObserverState(), short) == [[], []]
    bursty = LinkChecks(small_scenario(comms=BURSTY), "ground", LOG)
    assert _windows(bursty, ObserverState(), cut, sent=late) == [[], [], []]


def test_a_silence_already_declared_or_out_of_reach_is_not_declared_again() -> None:
    links = LinkChecks(small_scenario(comms={"packet_loss": 0.1}), "ground", LOG)
    silent = {600.0: [590.0], 630.0: [], 660.0: [640.0]}  # the silent window declares it
    assert [len(r) for r in _windows(links, ObserverState(), silent)] == [0, 1, 0]
    obs = ObserverState()
    _windows(links, obs, {600.0: [590.0]})
    assert _windows(links, obs, {630.0: []}, reachable=False) == [[]]  # out of reach: no gap
    assert _windows(links, obs, {660.0: [640.0]}) == [[]]


def test_a_window_losing_more_than_its_link_explains_is_lossy() -> None:
    """At a nominal 5%: 1 of 10 lost is healthy (P = 0.40), 4 of 10 is not (P = 1e-3), and a
    silent window with its camera on is (with it off it says nothing)."""
    links = LinkChecks(small_scenario(comms={"packet_loss": 0.05}), "ground", LOG)
    obs = ObserverState()
    flags = []
    for k, (missing, received) in enumerate([(0, 10), (1, 9), (4, 6), (0, 10)]):
        first = obs.last_seq + missing + 1
        images = [_obs(1, 10.0 * k + i, first + i) for i in range(received)]
        links.judge(1, obs, images, True, 10.0 * (k + 1))
        flags.append(obs.lossy)
    assert flags == [False, False, True, False]
    links.judge(1, obs, [], True, 50.0)
    assert obs.lossy
    links.judge(1, obs, [], False, 60.0)
    assert not obs.lossy


def test_a_dump_losing_more_than_its_link_explains_is_a_link_fault() -> None:
    """The store sends a lost message again, so the loss shows in its accounting only: on a
    15% link, 15 of 100 transmissions lost is healthy, 90 of 100 a link fault (once per
    episode, until a dump window within the limit); a window not over, or with nothing
    dumped (between passes), decides nothing."""
    links = LinkChecks(small_scenario(comms={"packet_loss": 0.15}), "ground", LOG)
    obs, dumped, again, out = ObserverState(), 0, 0, []
    for t, sent, lost in [(0, 0, 0), (30, 100, 15), (45, 100, 90), (60, 100, 90), (90, 100, 90),
                          (120, 0, 0), (150, 100, 10), (180, 100, 90)]:
        dumped, again = dumped + sent - lost, again + lost
        out.append(len(links.dump(1, obs, StoreCounter(dumped=dumped, retransmitted=again),
                                  float(t))))
    assert out == [0, 0, 0, 1, 0, 0, 0, 1]
    assert obs.dump_declared


def _lossy_windows(links: LinkChecks, missing: list[int], received: int = 10
                  ) -> list[tuple[int, list[FaultReport]]]:
    """Windows of ``received`` observations after ``missing[k]`` lost ones (none received when
    ``received`` is 0 and the window has a plan)."""
    obs, seq, out = ObserverState(), 0, []
    for k, m in enumerate(missing):
        seq += m
        images = [_obs(1, 10.0 * k + i, seq + i + 1) for i in range(received)]
        seq += received
        out.append(links.judge(1, obs, images, True, 10.0 * (k + 1)))
    return out


def test_loss_beyond_the_links_limit_for_two_windows_is_a_link_fault() -> None:
    """5 of 15 missing at a nominal 5%: beyond the limit (0.1 + 0.05 + 2σ), but a healthy link
    does it with probability 6e-3, above the window's one-window share (8.3e-5): two windows."""
    scenario = small_scenario(comms={"packet_loss": 0.05}, fdir={"loss_tol": 0.1,
                                                                 "checks_persistence": 2})
    links = LinkChecks(scenario, "ground", LOG)
    assert links.limit(15) == pytest.approx(0.15 + 2 * (0.05 * 0.95 / 15) ** 0.5)
    assert not links.decisive(5, 15)
    out = _lossy_windows(links, [5, 5, 5])
    assert [lost for lost, _ in out] == [5, 5, 5]
    assert [len(r) for _, r in out] == [0, 1, 0]
    assert out[1][1][0].metric == pytest.approx(5 / 15)


def test_one_window_decides_when_a_healthy_link_could_hardly_lose_as_much() -> None:
    """12 of 22 missing at a nominal 5% (probability 1e-11): declared on that window, once per
    episode however long it lasts (3 windows in a row to declare otherwise); with no nominal
    loss any loss beyond the limit decides; a loss declared, then silence, is one link fault."""
    scenario = small_scenario(comms={"packet_loss": 0.05}, fdir={"loss_tol": 0.1,
                                                                 "checks_persistence": 3})
    links = LinkChecks(scenario, "ground", LOG)
    assert links.alpha == pytest.approx(0.01 * 30.0 / 3600.0)
    assert links.decisive(12, 22)
    assert [len(r) for _, r in _lossy_windows(links, [12] * 5)] == [1, 0, 0, 0, 0]
    lossless = LinkChecks(small_scenario(comms={"packet_loss": 0.0}, fdir={"loss_tol": 0.1}),
                          "ground", LOG)
    assert [len(r) for _, r in _lossy_windows(lossless, [5, 5])] == [1, 0]
    links, obs = LinkChecks(scenario, "ground", LOG), ObserverState()
    images = [_obs(1, float(i), 12 + i + 1) for i in range(10)]
    assert len(links.judge(1, obs, images, True, 10.0)[1]) == 1
    assert [len(links.judge(1, obs, [], True, b)[1]) for b in (20.0, 30.0, 40.0)] == [0, 0, 0]


def test_the_window_after_a_silence_counts_its_missing_observations() -> None:
    """One silent window (not yet a link fault on a link losing 30% in bursts of 3), then 2
    received after 18 missing: 90% of 20 lost, beyond the link's limit (one window persists)."""
    links = LinkChecks(small_scenario(comms={"packet_loss": 0.3,
                                             "burst": {"mean_length_packets": 3.0}},
                                      fdir={"checks_persistence": 1, "loss_tol": 0.1}),
                       "ground", LOG)
    assert links.limit(20) < 0.9
    obs = ObserverState()
    first = [_obs(1, float(i), i + 1) for i in range(10)]
    assert links.judge(1, obs, first, True, 10.0) == (0, [])
    assert links.judge(1, obs, [], True, 20.0) == (0, [])
    lost, reports = links.judge(1, obs, [_obs(1, 21.0, 29), _obs(1, 22.0, 30)], True, 30.0)
    assert lost == 18 and [r.fault_class for r in reports] == ["link"]
    assert reports[0].metric == pytest.approx(0.9)


def test_an_observer_its_plan_puts_beyond_the_relays_reach_is_no_link_fault() -> None:
    """The ground is reached through the target: on a PRO 10-20 m from it with a 16 m range
    (15.05 m less the margin) the observer is out of reach half of each orbit.  Its silent
    windows there are no link fault, and the observations it could not send down are not
    lost: the next window in reach counts afresh."""
    n = 1.1e-3
    links = LinkChecks(small_scenario(comms={"range_m": 16.0}, fdir={"checks_persistence": 1}),
                       "ground", LOG)
    obs = ObserverState()
    obs.plans[1] = FlightPlan(0.0, Pro(10.0, 0.0, 0.0, 0.0, 0.0), None, None)
    starts = np.arange(0.0, 5700.0, 30.0)
    far = [float(np.linalg.norm(obs.planned(n, np.array([a, a + 29.0]))[0], axis=1).min())
           for a in starts]
    out_a = float(starts[int(np.argmax(far))])  # 20 m off: beyond reach
    in_a = next(float(a) for a, d in zip(starts, far, strict=True)
                if a > out_a and d < 12.0)
    assert not links.in_reach(obs, n, out_a, out_a + 30.0)
    assert links.in_reach(obs, n, in_a, in_a + 30.0)
    assert links.in_reach(ObserverState(), n, 0.0, 30.0)  # no plan: the deployment, in reach
    first = [_obs(1, out_a - 30.0 + i, i + 1) for i in range(30)]
    assert links.judge(1, obs, first, True, out_a) == (0, [])
    assert links.judge(1, obs, [], True, out_a + 30.0, reachable=False) == (0, [])
    assert obs.silent == 0 and not obs.link_declared
    back = [_obs(1, in_a + i, 1000 + i) for i in range(30)]  # 900-odd numbers never sent down
    assert links.judge(1, obs, back, True, in_a + 30.0) == (0, [])
    assert obs.lost == 0 and obs.received == 60
    assert [len(links.judge(1, obs, [], True, b)[1]) for b in (in_a + 60.0, in_a + 90.0)] \
        == [1, 0]  # silent in reach: a link fault, once


def test_window_context_judges_tracked_images_under_a_plan() -> None:
    obs = ObserverState()
    obs.modes = [(0.0, "slew"), (40.0, "track")]
    obs.plans[1] = FlightPlan(0.0, Pro(20.0, 0.0, 0.0, 25.0, 0.0), None, None)
    settled = SettledMap.of(PoiMap.uniform(10, 1.0, 1))
    images = [_obs(1, t, i) for i, t in enumerate((50.0, 69.0, 71.0, 75.0), 1)]
    n = 1.1e-3
    ctx, count, reason = window_context(1, obs, images, 60.0, 80.0, settled, n, settle_s=30.0)
    # tracking since 40 s: judged from 70 s on
    assert count == 2 and ctx is not None and reason is None
    assert list(ctx.times) == [71.0, 75.0]
    assert np.allclose(ctx.planned, obs.plans[1].positions(n, ctx.times))
    assert ctx.attitude is None and ctx.nav is None  # nothing reported: no pose
    assert ctx.h_prev == 0.0  # nothing fused yet
    assert window_context(1, obs, images[:2], 60.0, 80.0, settled, n, 30.0) == (None, 0,
                                                                                  "not_tracking")
    obs.plans.clear()
    assert window_context(1, obs, images, 60.0, 80.0, settled, n, 30.0) == (None, 4, "no_plan")


def _judgement(sc: int, metric: float, evidence: Evidence, model: RatioModel | None = None,
               dh: float = 0.5, dh_pred: float = 1.0) -> Judgement:
    failed = ["information"] if metric > 0.1 else []
    window = FdirWindow(sender="ground", t_sim=10.0, spacecraft=sc, t_start_s=0.0, t_end_s=10.0,
                        images=5, lost=0, dh=dh, dh_pred=dh_pred, metric=metric, threshold=0.1,
                        failed=failed, direction="degraded")
    return Judgement(window, evidence, WindowThreshold(model, None, None, 0.1, "model"))


def test_a_ratio_every_observer_shares_is_common_mode_declared_once() -> None:
    check = GlobalCheck(small_scenario().fdir, 1e-3, "ground", LOG)
    model = RatioModel(1.0, 0.01, 0.01, 0.0)
    judged = {sc: _judgement(sc, 0.5, Evidence(), model) for sc in (1, 2, 3)}
    verdict, out = check.check(0.0, 10.0, judged, cost=7.0)
    assert verdict is not None and verdict.common_mode and verdict.ratio == pytest.approx(0.5)
    window, report = out
    assert isinstance(window, ConstellationWindow) and window.observers == 3
    assert window.cost == 7.0 and window.shortfall == pytest.approx(1.5)  # Σ (ΔH_pred − ΔH)
    assert isinstance(report, FaultReport) and report.spacecraft == 0
    assert report.fault_class == "common_mode" and report.direction == "degraded"
    _, again = check.check(10.0, 20.0, judged, cost=6.0)
    assert len(again) == 1 and check.shortfall == pytest.approx(3.0)
    verdict, out = check.check(20.0, 30.0, {1: judged[1]}, cost=6.0)
    assert verdict is None and out[0].observers == 1  # too few observers to judge


def test_scans_crossing_together_declare_common_mode_at_once_then_are_its() -> None:
    """Every scored observer's scan crossed the same way: the constellation's common mode,
    declared at the latest crossing, once; while its episode goes on a crossing the same way
    is its, the other way an observer's own; a window not common ends the episode."""
    check = GlobalCheck(small_scenario().fdir, 1e-3, "ground", LOG)
    down = [Crossing(12.0, ScanResult(8.0, -8.0, 1), -0.08, 0.05),
            Crossing(13.0, ScanResult(9.0, -9.0, 2), -0.12, 0.05)]
    (report,) = check.declare_crossings(down, 13.0, 30.0)
    assert report.spacecraft == 0 and report.fault_class == "common_mode"
    assert report.t_sim == 13.0 and report.direction == "degraded"
    assert report.detector == "sequential" and report.metric == pytest.approx(0.12)
    assert check.declare_crossings(down, 14.0, 30.0) == []  # once per episode
    up = Crossing(20.0, ScanResult(8.0, 8.0, 1), 0.08, 0.05)
    assert check.explains(down[0]) and not check.explains(up)
    model = RatioModel(1.0, 0.01, 0.01, 0.0)
    same = {sc: _judgement(sc, 0.5, Evidence(), model) for sc in (1, 2, 3)}
    healthy = {sc: _judgement(sc, 0.0, Evidence(), model, dh=1.0) for sc in (1, 2, 3)}
    check.check(0.0, 30.0, healthy, cost=7.0)  # the change began late in it: not counted
    assert check.explains(down[0])
    _, out = check.check(30.0, 60.0, same, cost=7.0)
    assert len(out) == 1 and check.explains(down[0])  # the same episode, not again
    check.check(60.0, 90.0, healthy, cost=7.0)
    assert not check.explains(down[0])  # the episode ended


def test_declaration_after_persistence_with_the_class_the_evidence_shows() -> None:
    declarer = Declarer(small_scenario(fdir={"persistence": 2}).fdir, "ground", LOG)
    camera = Evidence(beta_hat=0.5)  # half the nominal health: a camera fault
    first = declarer.declare(1, _judgement(1, 0.5, camera), None)
    assert len(first) == 1 and first[0].exceeded is True
    second = declarer.declare(1, _judgement(1, 0.5, camera), None)
    assert [type(m) for m in second] == [FdirWindow, FaultReport]
    assert second[1].fault_class == "camera" and second[1].evidence == {"beta_hat": 0.5}
    assert not declarer.naming(1)  # declared and named: the episode goes on
    assert len(declarer.declare(1, _judgement(1, 0.5, camera), None)) == 1  # once per episode


def test_a_class_found_on_a_later_window_and_common_mode_not_held_against_one() -> None:
    declarer = Declarer(small_scenario().fdir, "ground", LOG)
    out = declarer.declare(2, _judgement(2, 0.5, Evidence()), None)
    assert out[1].fault_class is None and declarer.identifying(2)
    out = declarer.declare(2, _judgement(2, 0.5, Evidence(pointing_error_deg=5.0)), None)
    assert out[1].fault_class == "actuator" and not declarer.identifying(2)
    common = ConstellationVerdict(0.5, RatioModel(1.0, 0.01, 0.01, 0.0), 0.05, True, None)
    out = declarer.declare(3, _judgement(3, 0.5, Evidence(beta_hat=0.5)), common)
    assert out[0].exceeded is False and len(out) == 1
    # no verdict this window, but a common-mode episode the same way goes on: not its own
    out = declarer.declare(4, _judgement(4, 0.5, Evidence(beta_hat=0.5)), None, "degraded")
    assert out[0].exceeded is False and len(out) == 1
    out = declarer.declare(4, _judgement(4, 0.5, Evidence(beta_hat=0.5)), None, "improved")
    assert out[0].exceeded is True and out[1].fault_class == "camera"


def _integrity_over_two_boundaries(observers: dict[int, ObserverState],
                                   crosslink_loss: float = 0.0
                                   ) -> list[tuple[list[FaultReport], dict[int, str]]]:
    """The data-integrity check at boundaries 1 and 2 (10 s, 20 s) of two observers whose map
    the ground holds, sc1 reporting its H_i 1.5 times what its observations give."""
    cfg = small_scenario(fdir={"checks_persistence": 2, "integrity_tol": 0.2}).fdir
    check = IntegrityCheck(cfg, "ground", LOG, crosslink_loss=crosslink_loss)
    settled = PoiMap.uniform(10, 1.0, 2)
    settled.add(1, np.array([1, 2]), np.array([0.5, 0.5]))
    settled.add(2, np.array([2, 3]), np.array([0.5, 0.5]))
    truth = settled.contributions()
    views = FusedViews(80.0, np.tile(settled.F[None], (2, 1, 1)),
                       np.ones((2, 2)))  # each fused everything
    out = []
    for j in (1, 2):
        for sc, factor in ((1, 1.5), (2, 1.0)):  # sc1 inflates its H_i by half
            check.reported(InfoCostTelemetry(
                sender=f"sc{sc}", t_sim=10.0 * j, spacecraft=sc,
                h_i=factor * float(truth[sc - 1]), h_local=1.0, prior_term=0.5,
                pois_seen_own=2, pois_seen_fused=3, images=1, shared_received=1), j)
        out.append(check.check(j, 10.0 * j, settled, views, observers))
    return out


def test_a_reported_h_i_off_the_grounds_recomputation_is_a_data_integrity_fault() -> None:
    out = _integrity_over_two_boundaries({1: ObserverState(), 2: ObserverState()})
    assert [len(r) for r, _ in out] == [0, 1]
    assert [u for _, u in out] == [{}, {}]
    report = out[1][0][0]
    assert report.spacecraft == 1 and report.fault_class == "data_integrity"
    assert report.metric == pytest.approx(0.5)


def _starved_check(fused_of_sc2: int, received_of_sc2: int = 20
                   ) -> tuple[list[FaultReport], dict[int, str]]:
    """sc1 fused ``fused_of_sc2`` of the ``received_of_sc2`` images of sc2 the ground counts
    in its range (a packet-loss fault on sc2's links) and says so (``shared_by``); both report
    honestly: sc1 on its own precision and that share of sc2's."""
    cfg = small_scenario(fdir={"checks_persistence": 1, "integrity_tol": 0.2}).fdir
    check = IntegrityCheck(cfg, "ground", LOG)
    settled = PoiMap.uniform(10, 1.0, 2)
    settled.add(1, np.array([1, 2]), np.array([0.5, 0.5]))
    settled.add(2, np.array([1, 2]), np.array([2.0, 2.0]))
    counts = np.full((2, 2), float(received_of_sc2))
    views = FusedViews(80.0, np.tile(settled.F[None], (2, 1, 1)), counts)
    share = fused_of_sc2 / received_of_sc2
    view1 = settled.F[0] + share * settled.F[1]
    honest1 = float(np.sum(settled.phi * settled.F[0] / (settled.w_inv + view1) ** 2))
    for sc, h_i, by in ((1, honest1, {"2": fused_of_sc2}),
                        (2, float(settled.contributions()[1]), {"1": received_of_sc2})):
        check.reported(InfoCostTelemetry(
            sender=f"sc{sc}", t_sim=10.0, spacecraft=sc, h_i=h_i, h_local=1.0, prior_term=0.5,
            pois_seen_own=2, pois_seen_fused=2, images=1, shared_received=sum(by.values()),
            shared_by=by), 1)
    return check.check(1, 10.0, settled, views, {1: ObserverState(), 2: ObserverState()})


def test_an_observer_short_of_a_few_of_a_neighbours_images_reports_honestly() -> None:
    """sc1 fused 19 of sc2's 20 images: its honest H_i matches the ground's rebuilding of its
    view, each neighbour's part scaled to the count it says it fused: judged, no fault."""
    assert _starved_check(19) == ([], {})


def test_an_observer_starved_of_a_neighbours_images_is_not_judged() -> None:
    """sc1 fused 3 of sc2's 20 images (85% lost on the crosslinks): no count's rescaling gives
    the view it fused, so its report is not judged, and says why; sc2's still is."""
    assert _starved_check(3) == ([], {1: "crosslink_shortfall"})
    assert _starved_check(0) == ([], {1: "crosslink_shortfall"})


def test_no_integrity_verdict_rests_on_observations_lost_to_a_stores_overflow() -> None:
    """Lost is not corrupt: with 20% of sc2's observations lost aboard (its store's overflow
    runs), the ground's map cannot give what its observers fused, so no report is judged, and
    each says why."""
    observers = {1: ObserverState(received=100), 2: ObserverState(received=80,
                                                                 overflow_observations=20)}
    assert observers[2].lost_fraction() == pytest.approx(0.2)
    out = _integrity_over_two_boundaries(observers)
    assert [r for r, _ in out] == [[], []]
    assert [u for _, u in out] == [{1: "lost", 2: "lost"}] * 2


def test_no_integrity_verdict_when_the_crosslinks_lose_more_than_it_allows() -> None:
    """The crosslinks' nominal loss of 15% (above integrity_max_loss, 10%): every observer
    fused its neighbours' images less what they lost, which the ground cannot rebuild."""
    out = _integrity_over_two_boundaries({1: ObserverState(), 2: ObserverState()}, 0.15)
    assert [r for r, _ in out] == [[], []]
    assert [u for _, u in out] == [{1: "crosslink_loss", 2: "crosslink_loss"}] * 2
    assert [len(r) for r, _ in _integrity_over_two_boundaries(
        {1: ObserverState(), 2: ObserverState()}, 0.05)] == [0, 1]


def test_no_integrity_verdict_while_an_observer_s_latest_window_is_lossy() -> None:
    """sc2's latest window lost more than its link explains (a packet-loss fault that began
    in it, say), though its share lost since the start is small: no report is judged."""
    observers = {1: ObserverState(received=100), 2: ObserverState(received=99, lost=1,
                                                                 lossy=True)}
    out = _integrity_over_two_boundaries(observers)
    assert [r for r, _ in out] == [[], []]
    assert [u for _, u in out] == [{1: "lossy", 2: "lossy"}] * 2


def test_no_integrity_verdict_while_reports_before_the_boundary_are_still_aboard() -> None:
    """sc2's store still holds a report sent at 15 s: the boundary at 10 s is judged, the one
    at 20 s is not (its images are not all in the ground's map)."""
    observers = {1: ObserverState(), 2: ObserverState(aboard_since_s=15.0)}
    out = _integrity_over_two_boundaries(observers)
    assert [u for _, u in out] == [{}, {1: "aboard", 2: "aboard"}]
    assert [r for r, _ in out] == [[], []]  # the first failed report alone does not persist


def test_no_integrity_verdict_while_an_observer_is_not_heard_from() -> None:
    """sc2 sent nothing that reached the ground since the window's start (a cut link, or its
    dump still to come): what it shared with its neighbours may never reach the ground, so no
    report is judged until it is heard again."""
    cfg = small_scenario(fdir={"checks_persistence": 1}).fdir
    check = IntegrityCheck(cfg, "ground", LOG, period_s=10.0)
    settled = PoiMap.uniform(10, 1.0, 2)
    settled.add(1, np.array([1, 2]), np.array([0.5, 0.5]))
    views = FusedViews(80.0, np.tile(settled.F[None], (2, 1, 1)),
                       np.ones((2, 2)))
    observers = {1: ObserverState(heard_s=19.0), 2: ObserverState(heard_s=5.0)}
    report = InfoCostTelemetry(
        sender="sc1", t_sim=20.0, spacecraft=1, h_i=9.0, h_local=1.0, prior_term=0.5,
        pois_seen_own=2, pois_seen_fused=3, images=1, shared_received=1,
        shared_by={"2": 1})  # far off
    check.reported(report, 2)
    assert check.check(2, 20.0, settled, views, observers) == ([], {1: "not_heard"})
    observers[2].heard_s = 12.0  # heard in the window: judged, and found off
    check.reported(report, 2)
    reports, unjudged = check.check(2, 20.0, settled, views, observers)
    assert unjudged == {} and [r.fault_class for r in reports] == ["data_integrity"]


def test_no_silence_is_measured_on_a_link_whose_loss_was_declared() -> None:
    """A link whose loss was declared a fault loses runs of images: no further link fault from
    the gaps between those that come (one link fault, declared once)."""
    links = LinkChecks(small_scenario(comms={"packet_loss": 0.1}), "ground", LOG)
    obs = ObserverState()
    first = links.judge(1, obs, [_obs(1, 570.0, 1), _obs(1, 599.0, 30)], True, 600.0)[1]
    assert [r.fault_class for r in first] == ["link"] and links.loss.declared(1)
    later = links.judge(1, obs, [_obs(1, 640.0, 71), _obs(1, 641.0, 72)], True, 660.0)[1]
    assert later == []  # 41 s between 599 and 640 s: part of the declared loss
