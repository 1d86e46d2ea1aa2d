"""The guidance app on its own (no executive): an assignment received after its departure
(held for a ground pass) takes the transfer time it asked for from when it arrives, and an
assignment it cannot plan is refused in public (a plan not solved), so the ground judges it
against the orbit it keeps."""

from __future__ import annotations

from typing import Any

import numpy as np

from fsw.apps.guidance import GuidanceApp
from gnc.pro import Pro
from interfaces.contracts.messages import (
    ProAssignment,
    ProAssignments,
    ProElements,
    StateEstimate,
    TransferPlanMsg,
)
from tests.conftest import app_alone, small_scenario

START = Pro(20.0, 0.0, 0.0, 25.0, 0.0)
"""small_scenario's PRO for observer 1"""


def _guidance() -> tuple[Any, list[Any]]:
    return app_alone(GuidanceApp, small_scenario("g", duration_s=3000.0), "sc1", 1)


def _estimate(app: Any, t: float, x: np.ndarray) -> None:
    app.on_estimate(StateEstimate(sender="sc1", t_sim=t, spacecraft=1, x=x.tolist(),
                                  P=(np.eye(6) * 1e-4).tolist()))


def _assign(app: Any, t: float, depart: float, arrive: float) -> None:
    pro = ProElements(rho_x_m=22.0, alpha_x_rad=0.3, rho_y_m=0.0, rho_z_m=26.0,
                      alpha_z_rad=0.3)
    app.on_assignments(ProAssignments(sender="ground", t_sim=t, assignments=[ProAssignment(
        spacecraft=1, assignment_id=1, phase="p", pro=pro, t_depart_s=depart,
        t_arrive_s=arrive)]))


def _plans(sent: list[Any]) -> list[TransferPlanMsg]:
    return [m for m in sent if isinstance(m, TransferPlanMsg)]


def test_an_assignment_received_after_its_departure_takes_the_time_it_asks_for() -> None:
    """Asked to leave at 100 s and arrive at 700 s: received in time, it arrives at 700 s;
    received at 1,000 s (held for a pass), it arrives 600 s after, at 1,600 s."""
    arrivals = []
    for received in (90.0, 1000.0):
        app, sent = _guidance()
        t = 100.0 if received < 100.0 else received
        _estimate(app, t, START.state(app.n, t))
        _assign(app, received, 100.0, 700.0)
        app.step(t)
        (plan,) = _plans(sent)
        assert not plan.refused and plan.t_s[0] == t
        arrivals.append(plan.t_s[-1])
    assert arrivals == [700.0, 1600.0]


def test_an_assignment_it_cannot_plan_is_refused_in_public() -> None:
    """An estimate at the target's centre (no keep-out can hold): refused, published as a
    plan not solved with no nodes, and the previous orbit (none here) kept."""
    app, sent = _guidance()
    _estimate(app, 100.0, np.zeros(6))
    _assign(app, 90.0, 100.0, 700.0)
    app.step(100.0)
    (plan,) = _plans(sent)
    assert plan.refused and plan.status == "refused" and plan.t_s == []
    assert app.refused_id == 1 and app.assignment is None
