"""The flight library's hot paths that use gnc.quat (fsw/lib/attitude.py's plans,
fsw/lib/attitude_control.py's tracking torque, fsw/lib/mekf.py's steps) against the scipy
computation they replaced, to 1e-12."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.gnc.test_quat import TOL, _quats


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240611)


def test_plans_match_scipy_slerp(rng: np.random.Generator) -> None:
    """SlerpPlan.at / SlewPlan.at give scipy Slerp's quaternion (sign included) at any time."""
    from scipy.spatial.transform import Slerp

    from fsw.lib.attitude import SlewPlan, slerp_plan

    r0 = Rotation.random(random_state=rng)
    for r1 in (Rotation.random(random_state=rng), Rotation.from_quat(-r0.as_quat()),
               r0 * Rotation.from_rotvec([0.0, math.pi - 1e-9, 0.0])):
        plan = slerp_plan(r0, r1, 10.0, 70.0)
        ref = Slerp([10.0, 70.0], Rotation.concatenate([r0, r1]))
        for t in (10.0, 10.0 + 1e-9, 33.3, 70.0, *rng.uniform(10.0, 70.0, 5)):
            np.testing.assert_allclose(plan.at(t)[0].as_quat(), ref(t).as_quat(), rtol=0, atol=TOL)
        np.testing.assert_allclose(plan.at(99.0)[0].as_quat(), ref(70.0).as_quat(), rtol=0,
                                   atol=TOL)
    t_s = np.cumsum(rng.uniform(0.5, 3.0, 6))
    q = Rotation.random(6, random_state=rng).as_quat() * rng.choice([-1.0, 1.0], (6, 1))
    slew = SlewPlan(t_s=t_s, q=q, w=np.zeros((5, 3)), status="solved", converged=True,
                    iterations=1, norm_error=0.0, terminal_error_rad=0.0)
    ref = Slerp(t_s, Rotation.from_quat(q))
    for t in (*t_s, *rng.uniform(t_s[0], t_s[-1], 20)):
        np.testing.assert_allclose(slew.at(t)[0].as_quat(), ref(t).as_quat(), rtol=0, atol=TOL)


def test_tracking_torque_takes_quaternions(rng: np.random.Generator) -> None:
    """Rotation and (4,) quaternion inputs (either sign, any norm) give the same command."""
    from fsw.lib.attitude_control import AttitudeGains, tracking_torque

    gains = AttitudeGains.gains_for(10.0, 0.9, w_max_radps=0.05)
    jm = np.diag([0.1, 0.12, 0.08])
    for _ in range(5):
        r_est, r_des = Rotation.random(2, random_state=rng)
        w, wd, wdd, h = rng.standard_normal((4, 3)) * 0.01
        ref = tracking_torque(r_est, w, r_des, wd, wdd, jm, h, gains, 2e-3)
        got = tracking_torque(-2.0 * r_est.as_quat(), w, list(r_des.as_quat()), wd, wdd, jm, h,
                              gains, 2e-3)
        np.testing.assert_allclose(got[0], ref[0], rtol=0, atol=1e-15)
        assert got[1] == pytest.approx(ref[1], abs=TOL)
        assert ref[1] == pytest.approx((r_des.inv() * r_est).magnitude(), abs=1e-9)
    with pytest.raises(ValueError):
        tracking_torque(np.zeros(4), w, r_des, wd, wdd, jm, h, gains, 2e-3)


def test_mekf_attitude_steps_match_scipy(rng: np.random.Generator) -> None:
    """The MEKF's propagation, innovation and reset, one filter and a batch, as scipy composes."""
    from fsw.lib.mekf import error_state, mekf_propagate, mekf_update

    q = _quats(rng)[:20] * 1.5  # any sign and norm
    b = rng.standard_normal((20, 3)) * 1e-4
    w = rng.standard_normal((20, 3)) * 0.2
    P = np.tile(np.diag([1e-6] * 3 + [1e-10] * 3), (20, 1, 1))
    r = Rotation.from_quat(q)
    q_prop = (r * Rotation.from_rotvec((w - b) * 0.1)).as_quat(canonical=True)
    q_meas = (r * Rotation.from_rotvec(rng.standard_normal((20, 3)) * 1e-3)).as_quat()
    for k in (None, 3):
        sel = slice(None) if k is None else k
        q1, _, _ = mekf_propagate(q[sel], b[sel], P[sel], w[sel], 0.1, 4e-5, 2e-7)
        np.testing.assert_allclose(q1, q_prop[sel], rtol=0, atol=TOL)
        nu = (r[sel].inv() * Rotation.from_quat(q_meas[sel])).as_rotvec()
        np.testing.assert_allclose(error_state(q[sel], b[sel], q_meas[sel], b[sel])[..., :3], nu,
                                   rtol=0, atol=TOL)
        # P_att = R = 1e-6 I and no attitude-bias correlation: gain ½ I on the attitude
        q2, b2, _, _ = mekf_update(q[sel], b[sel], P[sel], -q_meas[sel], np.eye(3) * 1e-6)
        expected = (r[sel] * Rotation.from_rotvec(0.5 * nu)).as_quat(canonical=True)
        np.testing.assert_allclose(q2, expected, rtol=0, atol=TOL)
        np.testing.assert_allclose(b2, b[sel], rtol=0, atol=0)
