"""The compiled attitude kernels against their numpy references, on random inputs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsw.lib import attitude_kernels as kern
from fsw.lib import mekf
from fsw.lib.attitude import repoint
from fsw.lib.attitude_control import AttitudeGains, tracking_torque
from gnc import quat
from gnc.frames import lvlh_to_eci_quat

TOL = 1e-12


def _unit_quat(rng: np.random.Generator) -> np.ndarray:
    return quat.normalize(rng.normal(size=4))


def _cov(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    a = rng.normal(size=(n, n)) * scale
    return a @ a.T + np.eye(n) * scale**2


@pytest.mark.parametrize("seed", range(20))
def test_mekf_propagate_matches_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    q, b, P = _unit_quat(rng), rng.normal(size=3) * 1e-4, _cov(rng, 6, 1e-3)
    # small and large rotations per step: both branches of the Φ coefficients
    w = rng.normal(size=3) * (1e-3 if seed % 2 else 0.5)
    dt = float(rng.uniform(0.01, 1.0))
    ref = mekf.mekf_propagate(q, b, P, w, dt, 1e-5, 1e-7)
    fast = kern.mekf_propagate(q, b, P, w, dt, 1e-5, 1e-7)
    for r, f in zip(ref, fast, strict=True):
        np.testing.assert_allclose(f, r, rtol=1e-11, atol=TOL)


@pytest.mark.parametrize("seed", range(20))
def test_mekf_update_matches_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    q, b, P = _unit_quat(rng), rng.normal(size=3) * 1e-4, _cov(rng, 6, 1e-3)
    q_meas = quat.normalize(q + rng.normal(size=4) * 1e-3) * (-1.0 if seed % 3 == 0 else 1.0)
    R = np.diag(rng.uniform(1e-9, 1e-7, size=3))
    ref = mekf.mekf_update(q, b, P, q_meas, R)
    fast = kern.mekf_update(q, b, P, q_meas, R)
    for r, f in zip(ref, fast, strict=True):
        np.testing.assert_allclose(f, r, rtol=1e-9, atol=TOL)


@pytest.mark.parametrize("seed", range(30))
def test_repoint_matches_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    q, bore = _unit_quat(rng), rng.normal(size=3)
    los = rng.normal(size=3) * 10.0
    if seed == 0:  # line of sight exactly opposite the boresight: the half-turn branch
        los = -quat.rotate(q, bore)
    if seed == 1:  # already on the line of sight
        los = quat.rotate(q, bore) * 3.0
    np.testing.assert_allclose(kern.repoint(q, los, bore), repoint(q, los, bore), atol=TOL)


@pytest.mark.parametrize("seed", range(20))
def test_pointing_reference_is_repoint_and_central_differences(seed: int) -> None:
    rng = np.random.default_rng(seed)
    q, bore = _unit_quat(rng), np.array([0.0, 0.0, 1.0])
    los = rng.normal(size=(3, 3)) * 20.0
    los[0], los[2] = los[1] + rng.normal(size=3) * 0.2, los[1] + rng.normal(size=3) * 0.2
    h = 1.0
    q_des, w, wdot = kern.pointing_reference(q, los[0], los[1], los[2], bore, h)
    ref_des = repoint(q, los[1], bore)
    back = quat.log(quat.mul(quat.conj(repoint(ref_des, los[0], bore)), ref_des))
    ahead = quat.log(quat.mul(quat.conj(ref_des), repoint(ref_des, los[2], bore)))
    np.testing.assert_allclose(q_des, ref_des, atol=TOL)
    np.testing.assert_allclose(w, (back + ahead) / (2 * h), atol=TOL)
    np.testing.assert_allclose(wdot, (ahead - back) / h**2, atol=TOL)
    angle = float(np.linalg.norm(quat.log(quat.mul(quat.conj(q_des), q))))
    assert kern.angle_between(q_des, q) == pytest.approx(angle, abs=1e-12)


@pytest.mark.parametrize("seed", range(10))
def test_los_matches_frames_model(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, incl = 1.1e-3, math.radians(rng.uniform(0, 98))
    node, u0 = (0.0, 0.0) if seed == 0 else tuple(rng.uniform(-math.pi, math.pi, size=2))
    orbit = (incl, node, u0)
    t, t_est, t_tgt = 500.0 + rng.uniform(0, 1e4), 499.5, 498.0
    x = rng.normal(size=6) * np.array([30, 30, 30, 0.05, 0.05, 0.05])
    tgt, rate, acc = rng.normal(size=3), rng.normal(size=3) * 0.1, rng.normal(size=3) * 0.01
    aim = tgt + (rate + 0.5 * (t - t_tgt) * acc) * (t - t_tgt)
    r = x[:3] + x[3:] * (t - t_est)
    ref = quat.rotate(lvlh_to_eci_quat(t, n, *orbit), aim - r)
    np.testing.assert_allclose(kern.lvlh_to_eci_quat(t, n, *orbit),
                               lvlh_to_eci_quat(t, n, *orbit), atol=1e-15)
    np.testing.assert_allclose(kern.los_eci(t, n, *orbit, x, t_est, tgt, rate, acc, t_tgt), ref,
                               rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("seed", range(30))
def test_tracking_torque_matches_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    q_est, q_des = _unit_quat(rng), _unit_quat(rng)
    if seed % 2:  # small errors: the linear regime
        q_des = quat.normalize(q_est + rng.normal(size=4) * 1e-3)
    w, wd, wdd, h = (rng.normal(size=3) * s for s in (0.01, 0.01, 1e-3, 0.05))
    J = np.diag(rng.uniform(0.5, 3.0, size=3))
    w_max = None if seed % 3 == 0 else 0.02
    gains = AttitudeGains(kp=0.08, kd=0.5, w_max_radps=w_max)
    tau_max = 10.0 if seed % 5 == 0 else 1e-3  # saturated or not
    ref_tau, ref_angle = tracking_torque(q_est, w, q_des, wd, wdd, J, h, gains, tau_max)
    tau, angle = kern.tracking_torque(q_est, w, q_des, wd, wdd, J, h, gains.kp, gains.kd,
                                      -1.0 if w_max is None else w_max, tau_max)
    np.testing.assert_allclose(tau, ref_tau, rtol=1e-11, atol=1e-15)
    assert angle == pytest.approx(ref_angle, abs=1e-12)
    assert np.abs(tau).max() <= tau_max * (1 + 1e-12)


@pytest.mark.parametrize("seed", range(12))
def test_track_cycle_is_the_kernels_called_one_by_one(seed: int) -> None:
    """The fused tracking cycle gives the same bits as the separate kernels, and names a slew
    beyond the threshold and a line of sight that vanishes."""
    rng = np.random.default_rng(seed)
    n, t, h = 1.1e-3, float(rng.uniform(0.0, 5000.0)), 1.0
    orbit = (math.radians(51.6), *rng.uniform(-math.pi, math.pi, size=2))
    x_est = np.concatenate([rng.normal(size=3) * 40.0, rng.normal(size=3) * 0.05])
    target, rate, accel = rng.normal(size=3), rng.normal(size=3) * 0.01, rng.normal(size=3) * 1e-4
    q_est, w_est, h_w = _unit_quat(rng), rng.normal(size=3) * 1e-3, rng.normal(size=3) * 1e-3
    J, bore = np.diag(rng.uniform(0.5, 2.0, size=3)), np.array([0.0, 0.0, 1.0])
    threshold = math.radians(5.0) if seed % 3 == 0 else math.pi
    los = [kern.los_eci(t + d, n, *orbit, x_est, t - 0.4, target, rate, accel, t - 0.7)
           for d in (-h, 0.0, h)]
    q_des, w_des, wdot_des = kern.pointing_reference(q_est, *los, bore, h)
    angle = kern.angle_between(q_des, q_est)
    status, _, q_got, angle_got, tau_got = kern.track_cycle(
        t, h, n, *orbit, x_est, t - 0.4, target, rate, accel, t - 0.7, q_est, q_est, w_est, bore,
        J, h_w, 0.05, 0.4, 0.02, 0.01, threshold)
    assert np.array_equal(q_got, q_des) and angle_got == angle
    if angle > threshold:
        assert status == kern.SLEW and not tau_got.any()
    else:
        tau, _ = kern.tracking_torque(q_est, w_est, q_des, w_des, wdot_des, J, h_w, 0.05, 0.4,
                                      0.02, 0.01)
        assert status == kern.TRACKED and np.array_equal(tau_got, tau)
    on_target = x_est.copy()  # the spacecraft at the target, not moving: no line of sight
    on_target[:3], on_target[3:] = target, 0.0
    status, t_bad, *_ = kern.track_cycle(
        t, h, n, *orbit, on_target, t, target, np.zeros(3), np.zeros(3), t, q_est, q_est, w_est,
        bore, J, h_w, 0.05, 0.4, 0.02, 0.01, threshold)
    assert status == kern.NO_LINE_OF_SIGHT and t_bad == t - h
