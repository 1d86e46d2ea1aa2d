"""Bad or hostile input to the flight GNC apps (fsw/apps/attitude.py, fsw/apps/guidance.py), each
on a real in-process Bus with messages fed to its handlers: the attitude app's safe mode (zero
torque when its step fails), its estimate losing no rotation over a lost gyro sample, and
guidance refusing an assignment it cannot fly safely (the sim's command checks:
tests/sim/test_node.py; malformed commands: tests/interfaces/contracts/test_messages.py)."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fsw.apps.attitude import AttitudeApp
from fsw.apps.guidance import GuidanceApp
from interfaces.contracts.messages import (
    AttitudeEstimate,
    AttitudeMeasurement,
    PointingTarget,
    ProAssignment,
    ProAssignments,
    ProElements,
    StateEstimate,
)
from interfaces.runtime.app import AppContext
from interfaces.runtime.bus import Bus
from interfaces.runtime.transport import InprocNetwork
from tests.conftest import small_scenario


def _ctx(app_node: str = "sc1") -> AppContext:
    sc = small_scenario("apps", rates={"high_hz": 10.0, "mid_hz": 1.0, "low_hz": 0.1},
                        observers={"count": 2})
    bus = Bus(app_node, "apps", InprocNetwork().endpoint())
    return AppContext(bus=bus, scenario=sc, node=app_node, spacecraft=1,
                      rng=np.random.default_rng(0), log=logging.getLogger("test"))


def _capture(app: AttitudeApp | GuidanceApp) -> list[tuple[str, object]]:
    sent: list[tuple[str, object]] = []
    app.publish = lambda name, msg: sent.append((name, msg))  # type: ignore[method-assign]
    return sent


def test_attitude_app_commands_zero_torque_when_its_step_fails() -> None:
    """A pointing target on the spacecraft itself leaves no line of sight: the control law
    fails, the app still commands zero torque for the tick (safe mode) and raises for the
    executive to count; with a valid target the next tick controls again."""
    app = AttitudeApp(_ctx())
    sent = _capture(app)
    fix = AttitudeMeasurement(sender="sim", t_sim=0.0, spacecraft=1, gyro_radps=[0.01, 0, 0],
                              star_tracker=[0, 0, 0, 1], st_sigma_cross_rad=5e-5,
                              st_sigma_roll_rad=3e-4)
    app.on_sensors(fix)
    app.on_estimate(StateEstimate(sender="sc1", t_sim=0.0, spacecraft=1,
                                  x=[10.0, 0, 0, 0, 0, 0], P=np.eye(6).tolist()))
    app.on_target(PointingTarget(sender="sc1", t_sim=0.0, spacecraft=1,
                                 target_lvlh_m=[10.0, 0.0, 0.0]))
    with pytest.raises(ValueError):
        app.step(0.0)
    name, msg = sent[-1]
    assert name == "wheels" and msg.t_sim == 0.0 and not any(msg.torque_body_nm)  # type: ignore[attr-defined]
    app.on_target(PointingTarget(sender="sc1", t_sim=0.1, spacecraft=1, target_lvlh_m=[0, 0, 0]))
    app.on_sensors(fix.model_copy(update={"t_sim": 0.1, "star_tracker": None}))
    app.step(0.1)
    wheels = [m for name, m in sent if name == "wheels"]
    assert wheels[-1].t_sim == 0.1 and np.any(wheels[-1].torque_body_nm)  # type: ignore[attr-defined]


def _assignment(aid: int, rho: float, t_depart: float, t_arrive: float) -> ProAssignments:
    pro = ProElements(rho_x_m=rho, alpha_x_rad=0.0, rho_y_m=0.0, rho_z_m=rho, alpha_z_rad=0.0)
    return ProAssignments(sender="ground", t_sim=t_depart, assignments=[ProAssignment(
        spacecraft=1, assignment_id=aid, phase=f"p{aid}", pro=pro, t_depart_s=t_depart,
        t_arrive_s=t_arrive)])


def test_guidance_refuses_an_assignment_it_cannot_fly_safely_and_keeps_its_orbit() -> None:
    """A PRO inside the keep-out sphere has no safe transfer: guidance keeps holding the orbit
    it has, once, without retrying the refused command the ground keeps repeating."""
    app = GuidanceApp(_ctx())
    sent = _capture(app)
    from gnc.hcw import mean_motion, pro_state
    n = mean_motion(500e3)
    app.on_estimate(StateEstimate(sender="sc1", t_sim=0.0, spacecraft=1,
                                  x=pro_state(n, 20.0, 0.0, 0.0, 20.0, 0.0).tolist(),
                                  P=(1e-4 * np.eye(6)).tolist()))
    app.on_attitude(AttitudeEstimate(
        sender="sc1", t_sim=0.0, spacecraft=1, q_eci_body=[0, 0, 0, 1], q_lvlh_body=[0, 0, 0, 1],
        gyro_bias_radps=[0, 0, 0], sigma_att_rad=1e-4, target_lvlh_m=[0, 0, 0],
        pointing_error_rad=0.0, mode="track", torque_body_nm=[0, 0, 0]))
    app.on_assignments(_assignment(1, 20.0, 0.0, 0.0))
    app.step(0.0)
    assert app.assignment is not None and app.assignment.assignment_id == 1
    app.on_assignments(_assignment(2, 2.0, 10.0, 600.0))  # a 2 m PRO: inside the 8 m keep-out
    app.step(10.0)
    assert app.assignment.assignment_id == 1 and app.refused_id == 2 and app.plan is None
    app.on_assignments(_assignment(2, 2.0, 10.0, 600.0))  # repeated by the ground
    assert app.pending is None
    status = [m for name, m in sent if name == "status"]
    assert status[-1].mode == "hold" and status[-1].assignment_id == 1  # type: ignore[attr-defined]


def test_attitude_estimate_loses_no_rotation_over_a_lost_gyro_sample() -> None:
    """The MEKF propagates to each sample's own time: with the sample of t = 0.2 s lost, the
    attitude at 0.3 s still has turned by ω·0.3 s (constant rate, no bias)."""
    app = AttitudeApp(_ctx())
    _capture(app)
    w = np.array([0.0, 0.02, 0.01])

    def sample(t: float, fix: bool) -> AttitudeMeasurement:
        return AttitudeMeasurement(
            sender="sim", t_sim=t, spacecraft=1, gyro_radps=w.tolist(),
            star_tracker=[0, 0, 0, 1] if fix else None,
            st_sigma_cross_rad=5e-5 if fix else 0.0, st_sigma_roll_rad=3e-4 if fix else 0.0)

    for t, fix in ((0.0, True), (0.1, False), (0.3, False)):
        app.on_sensors(sample(t, fix))
        app.step(t)
    expected = Rotation.from_rotvec(w * 0.3)
    assert (Rotation.from_quat(app.q).inv() * expected).magnitude() < 1e-9
