"""The planner and the onboard FDIR's plan requests (ground/apps/planner.py): the ground's FDIR,
not a request, decides a recovery; a request from safe hold that no new assignment answers in
the planner's cycle gets the current plan issued again (safe hold ends only on a newer
assignment, so it must come); a request from a watchpoint trip changes nothing."""

from __future__ import annotations

from ground.apps.planner import MissionPlanner
from interfaces.contracts.messages import FaultReport, OnboardFdirEvent, ProAssignments
from tests.conftest import app_alone, small_scenario


def _planner() -> tuple[MissionPlanner, list]:
    sc = small_scenario("pl", observers={"count": 3, "start": "pro"}, target={"pois": 300})
    return app_alone(MissionPlanner, sc, "ground", None)


def _request(name: str, sc: int = 2) -> OnboardFdirEvent:
    return OnboardFdirEvent(sender=f"sc{sc}", t_sim=50.0, spacecraft=sc, event="plan_request",
                            name=name, fault_class="actuator")


def _ids(sent: list) -> list[int]:
    return [m.assignments[0].assignment_id for m in sent if isinstance(m, ProAssignments)]


def test_a_trip_request_changes_no_plan() -> None:
    planner, sent = _planner()
    planner.step(0.0)
    planner.on_onboard(_request("pointing_deg"))
    planner.step(10.0)
    assert _ids(sent) == [1, 1]


def test_a_safe_hold_request_is_answered_when_nothing_else_is_issued() -> None:
    planner, sent = _planner()
    planner.step(0.0)
    # the ground's declaration and the safe-hold request in one cycle: the recovery answers
    planner.on_fault(FaultReport(sender="ground", t_sim=40.0, spacecraft=2,
                                 fault_class="actuator", window_end_s=40.0))
    planner.on_onboard(_request("safe_hold"))
    planner.step(50.0)
    assert _ids(sent)[-1] == 2 and len(planner.plan.issued) == 2
    # a new episode: the recovery has nothing left to do, the request gets the plan again
    planner.on_fault(FaultReport(sender="ground", t_sim=300.0, spacecraft=2,
                                 fault_class="actuator", window_end_s=300.0))
    planner.on_onboard(_request("safe_hold"))
    planner.step(310.0)
    assert _ids(sent)[-1] == 3
    assert planner.plan.issued[-1].pros == planner.plan.issued[-2].pros
