"""The compiled truth integrators against their numpy references, on random states."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gnc import quat
from interfaces.contracts.scenario import load_scenario
from sim.actuators import WheelArray
from sim.attitude import AttitudeTruth
from sim.dynamics import RelativeTruth, circular_chief_eci
from sim.hardware import ObserverHardware
from tests.conftest import REPO

SCENARIOS = REPO / "deploy" / "scenarios"


@pytest.mark.parametrize("seed", range(8))
def test_attitude_rk4_matches_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 1 + seed % 5
    q0 = quat.normalize(rng.normal(size=(n, 4)))
    w0, h0 = rng.normal(size=(n, 3)) * 0.05, rng.normal(size=(n, 3)) * 0.01
    a = rng.normal(size=(n, 3, 3)) * 0.3
    J = a @ np.swapaxes(a, 1, 2) + np.eye(3) * 2.0
    fast, ref = (AttitudeTruth(q0, w0, J, h0, compiled=c) for c in (True, False))
    for _ in range(20):
        tau, ext = rng.normal(size=(n, 3)) * 1e-3, rng.normal(size=(n, 3)) * 1e-4
        fast.step(0.1, tau, substeps=1 + seed % 3, tau_ext_body=ext)
        ref.step(0.1, tau, substeps=1 + seed % 3, tau_ext_body=ext)
    for got, want in ((fast.q, ref.q), (fast.w, ref.w), (fast.h, ref.h),
                      (fast.mean_rate, ref.mean_rate)):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("seed", range(8))
def test_relative_rk4_matches_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, j2 = 1 + seed % 5, bool(seed % 2)
    chief = circular_chief_eci(500e3 + 100e3 * rng.random(), np.radians(98 * rng.random()))
    rel = np.hstack([rng.normal(size=(n, 3)) * 50.0, rng.normal(size=(n, 3)) * 0.05])
    fast, ref = (RelativeTruth(chief, rel, j2=j2, compiled=c) for c in (True, False))
    for k in range(30):
        accel = None if k % 3 == 0 else rng.normal(size=(n, 3)) * 1e-4
        fast.step(0.1, accel, substeps=1 + seed % 2)
        ref.step(0.1, accel, substeps=1 + seed % 2)
    np.testing.assert_allclose(fast.rel_lvlh(), ref.rel_lvlh(), rtol=1e-11, atol=1e-10)
    np.testing.assert_allclose(fast.chief_eci, ref.chief_eci, rtol=1e-14)


@pytest.mark.parametrize("seed", range(4))
def test_hardware_frame_and_thrust_glue_is_the_reference_to_the_bit(seed: int) -> None:
    """The compiled attitudes in LVLH and thrust acceleration are the numpy reference's
    floating-point operations in the same order: the same bits, commands running or not."""
    scenario = load_scenario(SCENARIOS / "default.toml")
    rng = np.random.default_rng(seed)
    frame = Rotation.from_quat(quat.normalize(rng.normal(size=4)))
    fast, ref = (ObserverHardware(scenario, frame, compiled=c) for c in (True, False))
    for k in range(scenario.observers.count):
        if k % 2 == seed % 2:
            force, duration = (rng.normal(size=3) * 0.01).tolist(), float(rng.uniform(0.0, 2.0))
            for hw in (fast, ref):
                hw.command_thrust(k, force, duration_s=duration, t_s=0.0)
        bias = rng.normal(size=3) * 1e-4
        for hw in (fast, ref):
            hw.force_bias_body[k] = bias
    for t in (0.0, 0.5, 1.0, 3.0):
        q_lvlh_eci = quat.normalize(rng.normal(size=4))
        assert np.array_equal(fast.q_lvlh_body(q_lvlh_eci), ref.q_lvlh_body(q_lvlh_eci))
        assert np.array_equal(fast.accel_lvlh(t, q_lvlh_eci), ref.accel_lvlh(t, q_lvlh_eci))


@pytest.mark.parametrize("seed", range(6))
def test_wheel_torque_is_the_reference_to_the_bit(seed: int) -> None:
    """Commands within and beyond the torque limit, momenta near and beyond their limit (the
    recomputed axes), faulty scale and bias: the same bits as numpy's clip/minimum/maximum."""
    rng = np.random.default_rng(seed)
    n = 1 + seed % 5
    fast, ref = (WheelArray(n, [1e-3, 1e-3, 2e-3], 0.05, compiled=c) for c in (True, False))
    if seed % 2:  # dead wheels and a bias
        scale = np.where(rng.random((n, 3)) < 0.3, 0.0, 1.0)
        bias = rng.normal(size=(n, 3)) * 1e-4
        for w in (fast, ref):
            w.torque_scale, w.torque_bias_nm = scale, bias
    for _ in range(50):
        cmd = rng.normal(size=(n, 3)) * 2e-3
        h = rng.choice([-1.0, 1.0], size=(n, 3)) * rng.uniform(0.0499, 0.0501, size=(n, 3))
        h[rng.random((n, 3)) < 0.3] = rng.normal(size=3)[0] * 0.01
        assert np.array_equal(fast.realise(cmd, h, 0.1), ref.realise(cmd, h, 0.1))


@pytest.mark.parametrize("seed", range(3))
def test_hardware_step_is_the_reference_to_the_bit(seed: int) -> None:
    """Δv spent, torques held and timed out, and the attitude they drive, over many ticks."""
    scenario = load_scenario(SCENARIOS / "default.toml")
    rng = np.random.default_rng(seed)
    frame = Rotation.from_quat(quat.normalize(rng.normal(size=4)))
    fast, ref = (ObserverHardware(scenario, frame, compiled=c) for c in (True, False))
    for k in range(60):
        t = 0.1 * k
        i = k % scenario.observers.count
        if k % 7 == 0:
            force = (rng.normal(size=3) * 0.01).tolist()
            for hw in (fast, ref):
                hw.command_thrust(i, force, duration_s=0.5, t_s=t)
        if k % 3 == 0:
            torque = (rng.normal(size=3) * 1e-3).tolist()
            for hw in (fast, ref):
                hw.command_wheels(i, torque, t_s=t)
        leak = rng.normal(size=3) * 1e-5  # a leak from tick 30 on
        for hw in (fast, ref):
            if k == 30:
                hw.force_bias_body[i] = leak
            hw.step(t, 0.1)
    assert np.array_equal(fast.dv_mps, ref.dv_mps)
    for got, want in ((fast.attitude.q, ref.attitude.q), (fast.attitude.w, ref.attitude.w),
                      (fast.attitude.h, ref.attitude.h)):
        assert np.array_equal(got, want)
