"""The onboard FDIR app (fsw/apps/fdir.py) and the apps its sequences command: a ground
declaration naming this spacecraft starts its class's sequence in the same step, once; a
watchpoint trips on settled samples only; and the rules by which a flight-side action never
fights the ground's re-plan (the app's docstring), each checked on the apps themselves."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from fsw.apps.camera import CameraApp
from fsw.apps.fdir import OnboardFdirApp
from fsw.apps.guidance import GuidanceApp
from fsw.apps.nav import NavApp
from interfaces.contracts.messages import (
    AttitudeEstimate,
    FaultReport,
    GuidanceStatus,
    Message,
    OnboardCommand,
    OnboardFdirEvent,
    ProAssignment,
    ProAssignments,
    ProElements,
    RelNavMeasurement,
    ThrustCommand,
)
from interfaces.runtime.app import App
from tests.conftest import app_alone, small_scenario


def _app(cls: type[App], **sections: Any) -> tuple[Any, list[Message]]:
    sc = small_scenario("ob", onboard_fdir={"enabled": True}, **sections)
    return app_alone(cls, sc, "sc2", 2)


def _report(sc: int, fault_class: str | None, t: float = 60.0) -> FaultReport:
    return FaultReport(sender="ground", t_sim=t, spacecraft=sc, fault_class=fault_class,  # type: ignore[arg-type]
                       window_end_s=t)


def _status(mode: str, assignment: int = 1, t: float = 60.0) -> GuidanceStatus:
    return GuidanceStatus(sender="sc2", t_sim=t, spacecraft=2, mode=mode,  # type: ignore[arg-type]
                          assignment_id=assignment)


def _commands(sent: list[Message]) -> list[str]:
    return [m.command for m in sent if isinstance(m, OnboardCommand)]


def _events(sent: list[Message]) -> list[tuple[str, str]]:
    return [(m.event, m.name) for m in sent if isinstance(m, OnboardFdirEvent)]


def test_an_actuator_declaration_starts_safe_hold_in_the_same_step_and_asks_for_a_plan() -> None:
    app, sent = _app(OnboardFdirApp)
    app.on_report(_report(3, "actuator"))  # another spacecraft's: not ours
    app.step(60.0)
    assert sent == []
    app.on_report(_report(2, "actuator"))
    app.step(60.1)
    assert _commands(sent) == ["safe_hold", "point_target"]
    assert _events(sent) == [("report", "actuator"), ("sequence", "safe_hold"),
                             ("plan_request", "safe_hold"), ("sequence", "request_plan")]
    assert all(m.t_sim == 60.1 for m in sent)
    request = [m for m in sent if isinstance(m, OnboardFdirEvent) and m.event == "plan_request"]
    assert request[0].fault_class == "actuator"


@pytest.mark.parametrize("fault_class, commands", [
    ("camera", ["camera_off"]), ("state_sensor", ["nav_reset"]), ("link", []), (None, [])])
def test_each_class_starts_its_own_sequence(fault_class: str | None, commands: list[str]) -> None:
    app, sent = _app(OnboardFdirApp)
    app.on_report(_report(2, fault_class))
    app.step(60.0)
    assert _commands(sent) == commands
    assert _events(sent)[0] == ("report", fault_class or "")


def test_a_class_is_acted_on_once_per_episode_and_again_after_recovery() -> None:
    app, sent = _app(OnboardFdirApp)
    app.on_report(_report(2, "actuator"))
    app.step(60.0)
    app.on_report(_report(2, "actuator", 90.0))  # the ground repeats itself: nothing new
    app.step(90.0)
    assert _commands(sent).count("safe_hold") == 1
    app.on_guidance(_status("hold"))  # guidance has not taken the command yet: no recovery
    app.on_guidance(_status("safe"))
    app.on_guidance(_status("safe"))
    app.step(100.0)
    assert ("recovered", "safe_hold") not in _events(sent)
    app.on_guidance(_status("hold", assignment=2))  # a newer assignment ended safe hold
    app.step(110.0)
    assert ("recovered", "safe_hold") in _events(sent)
    app.on_report(_report(2, "actuator", 150.0))  # a new episode
    app.step(150.0)
    assert _commands(sent).count("safe_hold") == 2


def _track(app: OnboardFdirApp, t: float, error_deg: float) -> None:
    app.on_attitude(AttitudeEstimate(
        sender="sc2", t_sim=t, spacecraft=2, q_eci_body=[0, 0, 0, 1], q_lvlh_body=[0, 0, 0, 1],
        gyro_bias_radps=[0, 0, 0], sigma_att_rad=1e-4, target_lvlh_m=[0, 0, 0],
        pointing_error_rad=np.radians(error_deg), mode="track", torque_body_nm=[0, 0, 0],
        wheel_momentum_nms=[0.001, 0, 0], star_tracker_age_s=0.0))
    app.step(t)


def test_pointing_trips_on_settled_samples_and_asks_for_a_plan_as_an_actuator() -> None:
    app, sent = _app(OnboardFdirApp)
    settle = app.settle_s
    for k in range(int(settle)):  # the slew's overshoot while settling: not judged
        _track(app, float(k), 4.0)
    assert _events(sent) == []
    _track(app, settle, 3.0)
    _track(app, settle + 1.0, 3.0)
    trip = [m for m in sent if isinstance(m, OnboardFdirEvent) and m.event == "trip"]
    assert [(m.name, m.limit, m.t_sim) for m in trip] == [("pointing_deg", 1.0, settle + 1.0)]
    assert trip[0].value == pytest.approx(3.0)
    asked = [m for m in sent if isinstance(m, OnboardFdirEvent) and m.event == "plan_request"]
    assert asked[0].fault_class == "actuator" and _commands(sent) == []
    _track(app, settle + 2.0, 0.2)
    assert _events(sent)[-1] == ("clear", "pointing_deg")


# --- the apps the sequences command: the rules that keep the ground's re-plan in charge ----

def _assignment(aid: int) -> ProAssignments:
    pro = ProElements(rho_x_m=20.0, alpha_x_rad=0.0, rho_y_m=0.0, rho_z_m=25.0, alpha_z_rad=0.0)
    return ProAssignments(sender="ground", t_sim=1.0, assignments=[ProAssignment(
        spacecraft=2, assignment_id=aid, phase="p", pro=pro, t_depart_s=0.0, t_arrive_s=0.0)])


def test_safe_hold_withholds_thrust_until_a_newer_assignment_and_never_changes_one() -> None:
    app, sent = _app(GuidanceApp)
    app.on_assignments(_assignment(1))
    app.on_command(OnboardCommand(sender="sc2", t_sim=10.0, spacecraft=2, command="safe_hold",
                                  sequence="safe_hold"))
    for t in (10.0, 20.0):
        app.on_assignments(_assignment(1))  # the uplink repeats the one in force
        app.step(t)
    modes = [m.mode for m in sent if isinstance(m, GuidanceStatus)]
    assert modes == ["safe", "safe"] and not any(isinstance(m, ThrustCommand) for m in sent)
    assert app.pending is not None and app.pending.assignment_id == 1  # kept, not dropped
    app.on_assignments(_assignment(2))  # the ground's re-plan
    app.step(30.0)
    assert app.safe_from is None and app.assignment is not None
    assert app.assignment.assignment_id == 2
    assert [m.mode for m in sent if isinstance(m, GuidanceStatus)][-1] != "safe"


def test_camera_off_stops_the_observations_and_point_target_aims_at_the_centre() -> None:
    app, sent = _app(CameraApp, camera={"pointing": "max_variance"})
    app.aim_goal = np.array([1.0, 2.0, 0.5])
    app.on_command(OnboardCommand(sender="sc2", t_sim=5.0, spacecraft=2, command="point_target",
                                  sequence="safe_hold"))
    app.step(5.0)
    assert not app.max_variance and np.array_equal(app.aim_goal, np.zeros(3))
    app.on_command(OnboardCommand(sender="sc2", t_sim=6.0, spacecraft=2, command="camera_off",
                                  sequence="camera_off"))
    assert app.off


def test_nav_reset_restarts_the_filter_from_the_next_measurement() -> None:
    app, sent = _app(NavApp)

    def meas(t: float) -> RelNavMeasurement:
        return RelNavMeasurement(sender="sim", t_sim=t, spacecraft=2, r_m=[10.0, 0.0, 5.0],
                                 v_mps=[0.0, 0.01, 0.0], sigma_r_m=0.1, sigma_v_mps=0.001)

    app.on_relnav(meas(1.0))
    app.step(1.0)
    app.on_command(OnboardCommand(sender="sc2", t_sim=2.0, spacecraft=2, command="nav_reset",
                                  sequence="nav_reset"))
    app.step(2.0)
    assert app.resets == 1 and app.x is None
    app.on_relnav(meas(3.0))
    app.step(3.0)
    assert app.x is not None and app.x[0] == 10.0
