"""The message models (interfaces/contracts/messages/) refuse what is not a message: every field
states its physical range and a value outside is a validation error, and malformed commands
(a star-tracker fix of zero norm or without its noise, an assignment arriving before it departs
or absurdly late, a PRO of a million kilometres) are invalid messages."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from interfaces.contracts import messages as m
from interfaces.contracts.messages import (
    AttitudeEstimate,
    AttitudeMeasurement,
    ProAssignment,
    ProElements,
    RelNavMeasurement,
    StateEstimate,
    ThrustCommand,
    TruthState,
    WheelCommand,
)


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


def test_malformed_commands_are_invalid_messages() -> None:
    with pytest.raises(ValidationError):
        AttitudeMeasurement(sender="sim", t_sim=0.0, spacecraft=1, gyro_radps=[0, 0, 0],
                            star_tracker=[0, 0, 0, 0], st_sigma_cross_rad=1e-5,
                            st_sigma_roll_rad=1e-4)
    with pytest.raises(ValidationError):
        AttitudeMeasurement(sender="sim", t_sim=0.0, spacecraft=1, gyro_radps=[0, 0, 0],
                            star_tracker=[0, 0, 0, 1])  # a fix without its noise
    pro = ProElements(rho_x_m=10, alpha_x_rad=0, rho_y_m=0, rho_z_m=10, alpha_z_rad=0)
    with pytest.raises(ValidationError):
        ProAssignment(spacecraft=1, assignment_id=2, phase="x", pro=pro, t_depart_s=100.0,
                      t_arrive_s=50.0)
    with pytest.raises(ValidationError):
        ProAssignment(spacecraft=1, assignment_id=2, phase="x", pro=pro, t_depart_s=0.0,
                      t_arrive_s=1e9)
    with pytest.raises(ValidationError):
        ProElements(rho_x_m=1e9, alpha_x_rad=0, rho_y_m=0, rho_z_m=10, alpha_z_rad=0)
