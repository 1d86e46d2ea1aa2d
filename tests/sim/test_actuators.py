"""Tests of the thruster and reaction-wheel models (sim.actuators).

References: hand-computed saturation / minimum-impulse-bit / momentum-limit cases, sample
statistics of the thruster noise against χ² and normal bounds (scipy.stats), closed-form
rotations for the LVLH conversion, and conservation of total angular momentum when the wheels
drive the truth attitude model into saturation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats
from scipy.spatial.transform import Rotation

from sim.actuators import ThrusterBank, WheelArray, accel_lvlh
from sim.attitude import AttitudeTruth

DT = 0.1


def _rngs(n: int, seed: int = 0) -> list[np.random.Generator]:
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n)]


# ----- thrusters ------------------------------------------------------------


def test_thruster_saturation_and_deadband() -> None:
    bank = ThrusterBank(f_max_n=1.0, min_impulse_ns=1e-3, noise_frac=0.0, rngs=_rngs(2))
    # impulses 0.05, 0.2, 9e-4 | 2e-3, 0, 0.3 N s
    cmd = np.array([[0.5, -2.0, 0.009], [-0.02, 0.0, 3.0]])
    f = bank.fire(cmd, DT)
    np.testing.assert_array_equal(f, [[0.5, -1.0, 0.0], [-0.02, 0.0, 1.0]])
    np.testing.assert_allclose(bank.impulse_ns, [1.5 * DT, 1.02 * DT], rtol=1e-15)
    np.testing.assert_array_equal(bank.pulses, [2, 2])


def test_thruster_nearest_rounding_of_small_impulses() -> None:
    mib = 1e-3
    bank = ThrusterBank(f_max_n=[1.0, 1.0, 0.008], min_impulse_ns=mib, noise_frac=0.0,
                        rngs=_rngs(1), mib_rounding="nearest")
    # impulses 0.6 MIB (-> one MIB), 0.4 MIB (-> nothing), 0.6 MIB on an axis whose f_max * dt < MIB
    f = bank.fire([[0.006, -0.004, -0.006]], DT)
    np.testing.assert_allclose(f, [[mib / DT, 0.0, -0.008]], rtol=1e-15)
    np.testing.assert_array_equal(bank.pulses, [2])


def test_thruster_noise_statistics_and_per_spacecraft_streams() -> None:
    n, ticks, frac = 64, 400, 0.05
    bank = ThrusterBank(f_max_n=1.0, min_impulse_ns=0.0, noise_frac=frac, rngs=_rngs(n, seed=3))
    cmd = np.tile([0.5, -0.25, 0.8], (n, 1))
    ratios = np.stack([bank.fire(cmd, DT) / cmd for _ in range(ticks)]).ravel()
    m = ratios.size
    assert abs(ratios.mean() - 1.0) < 4.0 * frac / math.sqrt(m)
    var_lo, var_hi = stats.chi2.ppf([0.0005, 0.9995], m - 1) / (m - 1)
    assert var_lo * frac**2 < ratios.var(ddof=1) < var_hi * frac**2
    # Spacecraft 0 sees the same noise alone, and whatever the others are commanded.
    alone = ThrusterBank(1.0, 0.0, frac, rngs=_rngs(n, seed=3)[:1])
    crowd = ThrusterBank(1.0, 0.0, frac, rngs=_rngs(n, seed=3))
    for k in range(20):
        other = np.full((n, 3), 0.1 * (k % 3))  # commands that change, and sometimes fire nothing
        other[0] = cmd[0]
        np.testing.assert_array_equal(alone.fire(cmd[:1], DT)[0], crowd.fire(other, DT)[0])


def test_accel_lvlh_closed_form_rotations() -> None:
    # Body x along LVLH y (90° about z), body x along LVLH -z (90° about y).
    rot = Rotation.from_rotvec([[0.0, 0.0, math.pi / 2], [0.0, math.pi / 2, 0.0]])
    a = accel_lvlh([[2.0, 0.0, 0.0], [2.0, 0.0, 1.0]], rot, [4.0, 2.0])
    np.testing.assert_allclose(a, [[0.0, 0.5, 0.0], [0.5, 0.0, -1.0]], atol=1e-15)
    rng = np.random.default_rng(1)
    f = rng.normal(size=(5, 3))
    r = Rotation.random(5, random_state=rng)
    a = accel_lvlh(f, r, 12.0)
    np.testing.assert_allclose(np.linalg.norm(a, axis=1), np.linalg.norm(f, axis=1) / 12.0,
                               rtol=1e-14)
    np.testing.assert_allclose(r.inv().apply(a) * 12.0, f, atol=1e-14)


def test_thruster_bad_input() -> None:
    bank = ThrusterBank(f_max_n=1.0, min_impulse_ns=1e-3, noise_frac=0.0, rngs=_rngs(2))
    with pytest.raises(ValueError):
        bank.fire([[np.nan, 0.0, 0.0], [0.0, 0.0, 0.0]], DT)
    with pytest.raises(ValueError):
        bank.fire(np.zeros((3, 3)), DT)
    with pytest.raises(ValueError):
        bank.fire(np.zeros((2, 3)), -1.0)
    with pytest.raises(ValueError):
        ThrusterBank(f_max_n=0.0, min_impulse_ns=1e-3, noise_frac=0.0, rngs=_rngs(1))
    with pytest.raises(ValueError):
        ThrusterBank(f_max_n=1.0, min_impulse_ns=1e-3, noise_frac=0.0, rngs=[])
    with pytest.raises(ValueError):
        accel_lvlh([1.0, 0.0, 0.0], Rotation.identity(), 0.0)
    np.testing.assert_array_equal(bank.impulse_ns, 0.0)


# ----- reaction wheels ------------------------------------------------------


def test_wheel_torque_and_momentum_limits() -> None:
    h_max, tau_max = 0.02, 1e-3
    wheels = WheelArray(1, tau_max_nm=tau_max, h_max_nms=h_max)
    # Motor limit only.
    np.testing.assert_array_equal(wheels.realise([[5e-4, -3e-3, 2e-3]], np.zeros((1, 3)), DT),
                                  [[5e-4, -tau_max, tau_max]])
    # h_dot = -tau: at +h_max a negative torque grows the wheel -> zero; positive unloads -> passes.
    h = np.array([[h_max, h_max, -h_max]])
    np.testing.assert_array_equal(wheels.realise([[-5e-4, 5e-4, 5e-4]], h, DT), [[0.0, 5e-4, 0.0]])
    # Would cross the limit within the tick: the constant torque that ends exactly at the limit.
    h = np.array([[h_max - 2e-5, 0.0, -h_max + 1e-5]])
    tau = wheels.realise([[-5e-4, -5e-4, 5e-4]], h, DT)
    np.testing.assert_allclose(tau, [[-2e-4, -5e-4, 1e-4]], rtol=1e-9)
    np.testing.assert_allclose((h - tau * DT)[0, [0, 2]], [h_max, -h_max], rtol=1e-14)
    # Beyond the limit (e.g. initial condition): no growth, not forced back, unloading allowed.
    h = np.array([[1.5 * h_max, 1.5 * h_max, 0.0]])
    np.testing.assert_array_equal(wheels.realise([[-5e-4, 5e-4, 0.0]], h, DT), [[0.0, 5e-4, 0.0]])


def test_wheel_fault_hooks() -> None:
    wheels = WheelArray(2, tau_max_nm=[1e-3, 1e-3, 2e-3], h_max_nms=0.05)
    wheels.torque_scale = [[0.5, 0.0, 1.0], [1.0, 1.0, 1.0]]
    wheels.torque_bias_nm = [[0.0, 1e-4, 3e-3], [0.0, 0.0, 0.0]]
    tau = wheels.realise([[4e-4, 4e-4, 1e-4], [4e-4, 4e-4, 1e-4]], np.zeros((2, 3)), DT)
    np.testing.assert_allclose(tau, [[2e-4, 1e-4, 2e-3], [4e-4, 4e-4, 1e-4]], rtol=1e-15)
    with pytest.raises(ValueError):
        wheels.torque_scale = np.ones((3, 3))
    with pytest.raises(ValueError):
        wheels.realise([[np.nan, 0, 0], [0, 0, 0]], np.zeros((2, 3)), DT)


def test_wheels_saturate_in_the_truth_loop_and_conserve_momentum() -> None:
    h_max, tau_max = 0.01, 1e-3
    J = np.diag([0.05, 0.07, 0.09])
    n = 2
    wheels = WheelArray(n, tau_max_nm=tau_max, h_max_nms=h_max)
    truth = AttitudeTruth(Rotation.random(n, random_state=np.random.default_rng(4)).as_quat(),
                          np.zeros((n, 3)), J, np.zeros((n, 3)))
    H0 = truth.angular_momentum_eci()
    cmd = np.array([[8e-4, -3e-4, 5e-4], [-1e-3, 2e-4, 0.0]])
    peak = 0.0
    for _ in range(400):  # 40 s: every commanded wheel saturates within ~50 s of growth at most
        truth.step(DT, wheels.realise(cmd, truth.h, DT))
        peak = max(peak, float(np.max(np.abs(truth.h))))
    assert peak <= h_max * (1.0 + 1e-12)
    np.testing.assert_allclose(np.abs(truth.h[0, 0]), h_max, rtol=1e-12)  # saturated on x
    np.testing.assert_allclose(np.abs(truth.h[1, 0]), h_max, rtol=1e-12)
    np.testing.assert_allclose(truth.angular_momentum_eci(), H0, atol=1e-12)
    # Once saturated, the wheel no longer torques the body: the remaining motion is torque-free.
    assert np.all(np.abs(wheels.realise(cmd, truth.h, DT)[:, 0]) < 1e-15)
