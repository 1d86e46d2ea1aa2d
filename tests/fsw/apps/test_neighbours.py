"""The neighbours' FDIR app (fsw/apps/neighbours.py) fed by hand, as observer 1 of three: it
judges each neighbour's window ``fdir.latency_s`` after it closes (observer 2's camera at
β = 0.3 fails, observer 3 passes), shares its verdicts, and one ω_mid cycle later declares
observer 2 with observer 3's agreeing verdict; the plan a neighbour flies is the one its
guidance status reports (none while a transfer or a change of assignment falls in the window,
nor while its reports are too sparse to tell); a declared neighbour is still judged, and
cleared after windows agreed passing; the ground's overruling fuses the held observations
again."""

from __future__ import annotations

import numpy as np
import pytest

from fsw.apps.neighbours import NeighboursApp
from gnc.pro import Pro
from gnc.sequential_test import scan_threshold
from gnc.twin import centre_boresights
from interfaces.contracts.messages import (
    GuidanceStatus,
    Message,
    NeighbourCrossing,
    NeighbourDeclaration,
    NeighbourJudgement,
    NeighbourRuling,
    NeighbourVerdict,
    PoiObservations,
    ProElements,
    ReportedPose,
)
from tests.conftest import app_alone, small_scenario

SC = small_scenario("nb", target={"radius_m": 5.0, "pois": 1000},
                    camera={"half_angle_deg": 12.0}, rates={"fdi_period_s": 30.0},
                    neighbours={"enabled": True}, fdir={"detector": "window"})
"""The window test (Eq. 9 per window) aboard; ``SEQ``: the sequential test, the default."""
PROS = {2: Pro(10.0, 0.3, 0.0, 15.0, 1.1), 3: Pro(10.0, 2.4, 0.0, 15.0, 3.2)}


def _app() -> tuple[NeighboursApp, list[Message]]:
    app, sent = app_alone(NeighboursApp, SC)
    for t in np.arange(0.0, 70.0, 10.0):
        for sc in PROS:
            app.on_guidance(_status(sc, float(t)))
    return app, sent


def _status(sc: int, t: float, aid: int = 1, mode: str = "hold") -> GuidanceStatus:
    """Observer ``sc``'s guidance status at ``t`` (s): flying assignment ``aid`` to its PRO."""
    p = PROS[sc]
    return GuidanceStatus(sender=f"sc{sc}", seq=int(t) + 1, t_sim=t, spacecraft=sc, mode=mode,
                          assignment_id=aid, pro=ProElements(
                              rho_x_m=p.rho_x_m, alpha_x_rad=p.alpha_x_rad, rho_y_m=p.rho_y_m,
                              rho_z_m=p.rho_z_m, alpha_z_rad=p.alpha_z_rad))


def _images(app: NeighboursApp, sc: int, beta: float) -> list[PoiObservations]:
    """A window [30, 60) of images from the PRO, aimed at the target centre, at β."""
    times = np.arange(30.0, 60.0)
    pos = PROS[sc].states(app.n, times)[:, :3]
    prec = app.twin.precision(pos, centre_boresights(pos))
    out = []
    for t, p, row in zip(times, pos, prec, strict=True):
        seen = np.flatnonzero(row > 0.0)
        pose = ReportedPose(nav_m=list(p), nav_sigma_m=0.05, aim_m=[0.0, 0.0, 0.0],
                            knowledge_rad=1e-4, tracking_rad=2e-4, tracking_s=500.0)
        out.append(PoiObservations(sender=f"sc{sc}", seq=int(t), t_sim=float(t), spacecraft=sc,
                                   image_t_s=float(t), poi=seen.tolist(),
                                   precision=(beta * row[seen]).tolist(), pose=pose))
    return out


def test_it_judges_its_neighbours_and_declares_by_agreement() -> None:
    app, sent = _app()
    for m in [*_images(app, 2, 0.3), *_images(app, 3, 1.0)]:
        app.on_observations(m)
    app.step(60.0 + SC.fdir.latency_s - 0.5)
    assert sent == []  # not yet due
    app.step(60.0 + SC.fdir.latency_s)
    (judgement,) = sent
    assert isinstance(judgement, NeighbourJudgement)
    assert (judgement.spacecraft, judgement.t_start_s, judgement.t_end_s) == (1, 30.0, 60.0)
    assert {v.subject: v.exceeded for v in judgement.verdicts} == {2: True, 3: False}
    app.on_judgement(judgement)  # its own comes back through the bus
    app.on_judgement(NeighbourJudgement(
        sender="sc3", seq=1, t_sim=judgement.t_sim, spacecraft=3, t_start_s=30.0, t_end_s=60.0,
        verdicts=[NeighbourVerdict(subject=2, images=30, exceeded=True),
                  NeighbourVerdict(subject=1, images=30, exceeded=False)]))
    app.step(60.0 + SC.fdir.latency_s + 1.0 / SC.rates.mid_hz)
    (declaration,) = [m for m in sent if isinstance(m, NeighbourDeclaration)]
    assert (declaration.subject, declaration.judges, declaration.decided) == (2, [1, 3], [1, 3])
    assert app.declared == {2} and app.exclusions.since_s == {2: 60.0}


def test_a_neighbour_is_judged_on_the_pro_its_guidance_reports_holding() -> None:
    app, _ = _app()
    assert app._pro(2, 30.0, 60.0) == PROS[2]
    app.on_guidance(_status(2, 70.0, aid=2, mode="transfer"))  # a new assignment from 70 s
    for t in (80.0, 90.0):
        app.on_guidance(_status(2, t, aid=2))
    assert app._pro(2, 60.0, 90.0) == "transfer"  # a transfer in the window
    app.on_guidance(_status(2, 100.0, aid=3))  # a change of assignment without a transfer
    assert app._pro(2, 90.0, 120.0) == "transfer"
    for t in (70.0, 80.0, 90.0):
        app.on_guidance(_status(3, t))
    for t in (100.0, 110.0, 120.0):
        app.on_guidance(_status(3, t, mode="safe"))
    assert app._pro(3, 90.0, 120.0) == "no_plan"  # in safe hold: flies no plan
    assert app._pro(3, 150.0, 180.0) == "plan_unknown"  # nothing reported since 120 s
    assert app._pro(4, 30.0, 60.0) == "plan_unknown"  # never heard


def test_a_lost_report_leaves_the_plan_known_a_lost_pair_does_not() -> None:
    app, sent = _app()
    for t in (70.0, 90.0):  # the report at 80 s was lost
        app.on_guidance(_status(2, t))
    assert app._pro(2, 60.0, 90.0) == PROS[2]
    app.on_guidance(_status(2, 120.0))  # those at 100 and 110 s too
    assert app._pro(2, 90.0, 120.0) == "plan_unknown"
    for m in _images(app, 2, 1.0):
        app.on_observations(m.model_copy(update={"image_t_s": m.image_t_s + 60.0}))
    app.step(120.0 + SC.fdir.latency_s)
    (verdict,) = [v for j in sent for v in j.verdicts if j.t_start_s == 90.0]
    assert verdict.exceeded is None and verdict.unjudged == "plan_unknown"


def test_a_declared_neighbour_is_still_judged_and_cleared_when_it_passes() -> None:
    app, sent = _app()
    app.declared.add(2)
    app.exclusions.exclude(2, 30.0)
    for m in _images(app, 2, 1.0):
        app.on_observations(m)
    app.step(60.0 + SC.fdir.latency_s)
    (judgement,) = sent
    assert {v.subject: v.exceeded for v in judgement.verdicts} == {2: False}
    for k in range(1, SC.neighbours.clear_windows + 1):  # windows agreed passing, in a row
        app.on_judgement(judgement.model_copy(update={"t_start_s": 30.0 * k,
                                                      "t_end_s": 30.0 * (k + 1)}))
        app.next_judge = k + 1
        assert app.declared == {2}
        app.step(30.0 * (k + 1) + SC.fdir.latency_s + 1.0 / SC.rates.mid_hz)
    assert app.declared == set() and app.exclusions.since_s == {}


def test_an_overruled_neighbour_is_fused_again() -> None:
    app, _ = _app()
    app.declared.add(2)
    app.exclusions.exclude(2, 30.0)
    held = _images(app, 2, 1.0)
    for m in held:
        app.on_observations(m)
        app.exclusions.admits(m)
    app.on_ruling(NeighbourRuling(sender="ground", seq=1, t_sim=90.0, subject=2,
                                  window_end_s=30.0, verdict="overruled"))
    assert app.declared == set() and app.exclusions.since_s == {}
    assert [m for m in app.pending if m.spacecraft == 2] == held + held


SEQ = SC.model_copy(update={"fdir": SC.fdir.model_copy(update={"detector": "sequential"})})


def test_with_the_sequential_test_a_neighbour_is_declared_mid_window() -> None:
    """The judge scans each neighbour's images as they come (the ground's image scan): the
    camera at β = 0.3 crosses on its first judged image, the one at β = 1 never; the crossing
    is shared at once, and with a second judge's the neighbour is declared before its
    window ends, from the first crossing's time."""
    app, sent = app_alone(NeighboursApp, SEQ)
    for t in np.arange(0.0, 70.0, 10.0):
        for sc in PROS:
            app.on_guidance(_status(sc, float(t)))
    app.step(30.0 + SEQ.fdir.latency_s)  # window [0, 30) judged: [30, 60) is scored
    for m in [*_images(app, 2, 0.3), *_images(app, 3, 1.0)]:
        if m.image_t_s < 45.0:
            app.on_observations(m)
    app.step(45.0)
    (judgement,) = [m for m in sent if isinstance(m, NeighbourJudgement) and m.crossings]
    assert judgement.verdicts == [] and (judgement.t_start_s, judgement.t_end_s) == (30.0, 60.0)
    (crossing,) = judgement.crossings
    assert crossing.subject == 2 and crossing.direction == "degraded"
    assert 30.0 <= crossing.t_s <= 35.0 and crossing.shift == pytest.approx(-0.7, abs=0.1)
    app.on_judgement(judgement)
    app.step(46.0)
    assert not [m for m in sent if isinstance(m, NeighbourDeclaration)]  # agree = 2: one
    app.on_judgement(judgement.model_copy(update={"spacecraft": 3, "sender": "sc3"}))
    app.step(47.0)
    (declaration,) = [m for m in sent if isinstance(m, NeighbourDeclaration)]
    assert (declaration.subject, declaration.judges, declaration.t_sim) == (2, [1, 3], 47.0)
    assert declaration.crossed_s == crossing.t_s and app.exclusions.since_s == {2: 30.0}
    # half the budget (the window test has the other half), over an hour's images, 1 a second
    per_image = SEQ.fdir.false_alarms_per_observer_hour / 2.0 / 3600.0
    assert app.tests == 2 and app.scans.c == pytest.approx(scan_threshold(per_image))


def test_a_window_begun_before_the_scans_crossed_does_not_clear_their_declaration() -> None:
    """Declared on scans that crossed at 45 s: window [30, 60), passing on the whole (the
    fault began late in it), does not count towards clearing it; [60, 90) does."""
    app, _ = app_alone(NeighboursApp, SEQ)
    app.declared.add(2)
    app.crossed_at[2] = 45.0
    for a in (30.0, 60.0):
        for judge in (1, 3):
            app.on_judgement(NeighbourJudgement(
                sender=f"sc{judge}", seq=1, t_sim=a + 33.0, spacecraft=judge, t_start_s=a,
                t_end_s=a + 30.0, verdicts=[NeighbourVerdict(subject=2, images=30,
                                                             exceeded=False)]))
    app.next_judge = 3  # windows 0-2 judged aboard
    app.step(60.0 + SEQ.fdir.latency_s + 1.0)
    assert app.passing.get(2, 0) == 0
    app.step(90.0 + SEQ.fdir.latency_s + 1.0)
    assert app.passing == {2: 1} and app.declared == {2}


def test_judges_scans_agree_across_a_window_s_end() -> None:
    """Judge 3's scan crossed at 59 s (window [30, 60)), judge 1's at 64 s: one FDI period
    apart at most, they agree, on the first's window; crossings older than a period are
    forgotten."""
    app, sent = app_alone(NeighboursApp, SEQ)
    app.on_judgement(_crossing_of(3, 59.0))
    app.step(60.0)
    app.on_judgement(_crossing_of(1, 64.0))
    app.step(65.0)
    (declaration,) = [m for m in sent if isinstance(m, NeighbourDeclaration)]
    assert (declaration.t_start_s, declaration.judges, declaration.crossed_s) == (30.0, [1, 3],
                                                                                 59.0)
    late, sent_late = app_alone(NeighboursApp, SEQ)
    late.on_judgement(_crossing_of(3, 10.0))
    late.step(11.0)
    late.on_judgement(_crossing_of(1, 64.0))
    late.step(65.0)
    assert not [m for m in sent_late if isinstance(m, NeighbourDeclaration)]


def _crossing_of(judge: int, t: float) -> NeighbourJudgement:
    """Judge ``judge``'s scan crossing on observer 2 at its image of ``t`` (s)."""
    a = 30.0 * (t // 30.0)
    return NeighbourJudgement(sender=f"sc{judge}", seq=1, t_sim=t, spacecraft=judge,
                              t_start_s=a, t_end_s=a + 30.0, crossings=[NeighbourCrossing(
                                  subject=2, t_s=t, z=9.0, span=1, shift=-0.5, limit=0.1,
                                  direction="degraded")])
