"""Fault injection in the sim (faults/hardware.py): each kind acts on the truth as specified, is
switched on and off at its times, and its realised parameters are reproducible from the seed.
The pointing-actuator sizing is checked by closing the real attitude loop (fsw tracking law on
the sim's rigid-body truth and wheels) and measuring the steady error."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from faults.hardware import FaultInjector
from fsw.lib.attitude_control import gains_for, tracking_torque
from gnc import quat
from gnc.infocost import Camera
from gnc.poi import sphere_pois
from interfaces.contracts.rng import stream
from interfaces.contracts.scenario import Scenario
from sim.attitude import AttitudeTruth
from sim.camera import TruthCameras
from sim.dynamics import RelativeTruth, circular_chief_eci
from sim.hardware import ObserverHardware
from sim.sensors import RelNavSensor


def _scenario(*faults: dict) -> Scenario:
    return Scenario.model_validate({"name": "f", "seed": 5, "duration_s": 100.0,
                                    "observers": {"count": 2}, "faults": list(faults)})


def _injector(sc: Scenario, truth: object = None) -> FaultInjector:
    hw = ObserverHardware(sc, Rotation.identity())
    pos, nor = sphere_pois(300, 5.0)
    cams = TruthCameras(pos, nor, Camera(), np.array([0.0, 0.0, 1.0]), 0.05,
                        [stream(1, "camera", i) for i in (1, 2)])
    relnav = [RelNavSensor(0.1, 0.002, stream(1, "relnav", i)) for i in (1, 2)]
    return FaultInjector(sc, hw, cams, relnav, truth)  # type: ignore[arg-type]


def test_switches_on_at_start_and_off_at_end_once() -> None:
    sc = _scenario({"spacecraft": 2, "kind": "camera_degradation", "start_s": 10.0,
                    "end_s": 20.0, "magnitude": 0.4},
                   {"spacecraft": 1, "kind": "link_loss", "start_s": 0.0})
    inj = _injector(sc)
    first = inj.update(0.0)
    assert [(s.fault.kind, s.active) for s in first] == [("link_loss", True)]
    assert inj.update(5.0) == [] and inj.cameras.beta.tolist() == [1.0, 1.0]
    (on,) = inj.update(10.0)
    assert on.active and inj.cameras.beta.tolist() == [1.0, 0.4]
    assert inj.update(15.0) == []
    (off,) = inj.update(20.0)
    assert not off.active and inj.cameras.beta.tolist() == [1.0, 1.0]


def test_thruster_bias_is_a_continuous_force_counted_as_dv() -> None:
    sc = _scenario({"spacecraft": 1, "kind": "thruster_bias", "start_s": 0.0, "magnitude": 0.1})
    inj = _injector(sc)
    inj.update(0.0)
    f = np.array(inj.detail[0]["force_body_n"])
    assert np.linalg.norm(f) == pytest.approx(0.1 * sc.actuators.thruster_max_force_n, rel=1e-12)
    hw = inj.hardware
    q = np.array([0.0, 0.0, 0.0, 1.0])
    a = hw.accel_lvlh(0.0, q)  # no thrust command at all: the bias still pushes
    expect = quat.rotate(hw.q_lvlh_body(q), np.vstack([f, np.zeros(3)])) / sc.observers.mass_kg
    assert np.allclose(a, expect, rtol=0, atol=1e-15) and np.all(a[1] == 0.0)
    hw.step(0.0, 10.0)
    assert hw.dv_mps[0] == pytest.approx(np.abs(f).sum() * 10.0 / sc.observers.mass_kg)
    assert hw.dv_mps[1] == 0.0


def test_camera_faults_scale_the_information_and_rotate_the_boresight() -> None:
    sc = _scenario({"spacecraft": 1, "kind": "camera_degradation", "start_s": 0.0,
                    "magnitude": 0.3},
                   {"spacecraft": 2, "kind": "camera_misalignment", "start_s": 0.0,
                    "magnitude": 12.0})
    nominal = _injector(_scenario())
    faulty = _injector(sc)
    faulty.update(0.0)
    r = np.array([[0.0, 0.0, -20.0], [0.0, 0.0, -20.0]])
    q = np.tile([0.0, 0.0, 0.0, 1.0], (2, 1))  # boresight +z: at the target
    good, bad = nominal.cameras.images(r, q), faulty.cameras.images(r, q)
    assert np.array_equal(good[0].poi, bad[0].poi)  # same geometry, same noise draws...
    assert np.allclose(bad[0].precision, 0.3 * good[0].precision, rtol=1e-12)  # ...β times
    b_nom, b_bad = nominal.cameras.boresights_lvlh(q)[1], faulty.cameras.boresights_lvlh(q)[1]
    assert math.degrees(math.acos(b_nom @ b_bad)) == pytest.approx(12.0, abs=1e-9)
    assert len(bad[1].poi) < len(good[1].poi)  # the rotated camera sees less of the target


def test_nav_sensor_bias_offsets_the_measurement() -> None:
    sc = _scenario({"spacecraft": 2, "kind": "nav_sensor_bias", "start_s": 0.0, "magnitude": 2.5})
    nominal, faulty = _injector(_scenario()), _injector(sc)
    faulty.update(0.0)
    r, v = np.array([10.0, -5.0, 3.0]), np.array([0.01, 0.0, -0.02])
    (r0, v0), (r1, v1) = nominal.relnav[1].measure(r, v), faulty.relnav[1].measure(r, v)
    assert np.linalg.norm(r1 - r0) == pytest.approx(2.5, rel=1e-12) and np.array_equal(v0, v1)
    assert np.allclose(r1 - r0, faulty.detail[0]["bias_lvlh_m"], atol=1e-12)


def test_fault_parameters_are_reproducible_from_the_seed() -> None:
    fault = {"spacecraft": 1, "kind": "camera_misalignment", "start_s": 0.0, "magnitude": 5.0}
    a, b = _injector(_scenario(fault)), _injector(_scenario(fault))
    assert a.detail == b.detail
    other = Scenario.model_validate({**_scenario(fault).model_dump(), "seed": 6})
    assert _injector(other).detail != a.detail


@pytest.mark.parametrize("degrees", [2.0, 6.0])
def test_pointing_actuator_fault_leaves_the_stated_steady_error(degrees: float) -> None:
    """Close the nominal attitude loop (fsw tracking law, sim rigid body and wheels) on a fixed
    target attitude with the fault on: the error settles at the fault's magnitude, off the
    boresight (a pointing error, not a roll about it)."""
    sc = _scenario({"spacecraft": 1, "kind": "pointing_actuator", "start_s": 0.0,
                    "magnitude": degrees})
    inj = _injector(sc)
    inj.update(0.0)
    hw = inj.hardware
    J = np.diag(sc.observers.inertia_kg_m2)
    gains = gains_for(sc.attitude.settling_time_s)
    truth = AttitudeTruth(np.array([[0.0, 0.0, 0.0, 1.0]]), np.zeros((1, 3)), J, np.zeros((1, 3)))
    target = np.array([0.0, 0.0, 0.0, 1.0])
    dt = 0.1
    for _ in range(int(200.0 / dt)):  # > 6 settling times
        tau_cmd, _ = tracking_torque(truth.q[0], truth.w[0], target, np.zeros(3), np.zeros(3),
                                     J, truth.h[0], gains, sc.actuators.wheel_max_torque_nm)
        cmd = np.vstack([tau_cmd, np.zeros(3)])
        tau = hw.wheels.realise(cmd, np.vstack([truth.h, np.zeros((1, 3))]), dt)[:1]
        truth.step(dt, tau)
    boresight = quat.rotate(truth.q[0], np.array([0.0, 0.0, 1.0]))
    error_deg = math.degrees(math.acos(min(1.0, boresight[2])))
    assert error_deg == pytest.approx(degrees, rel=0.02)
    assert np.linalg.norm(truth.w[0]) < 1e-5  # settled, not drifting


def test_common_mode_calibration_fault_scales_every_camera() -> None:
    sc = _scenario({"spacecraft": 0, "kind": "camera_calibration", "start_s": 5.0,
                    "end_s": 9.0, "magnitude": 0.7})
    inj = _injector(sc)
    assert inj.update(0.0) == [] and inj.cameras.beta.tolist() == [1.0, 1.0]
    (on,) = inj.update(5.0)
    assert on.active and inj.cameras.beta.tolist() == [0.7, 0.7]
    inj.update(9.0)
    assert inj.cameras.beta.tolist() == [1.0, 1.0]


@pytest.mark.parametrize("spacecraft, kind", [(0, "camera_degradation"),
                                              (1, "camera_calibration")])
def test_common_mode_kinds_and_spacecraft_zero_go_together(spacecraft: int, kind: str) -> None:
    with pytest.raises(ValueError, match="observer"):
        _scenario({"spacecraft": spacecraft, "kind": kind, "start_s": 0.0, "magnitude": 0.5})


class _Recorder:
    """A truth that records the disturbances it is given (isolates the injector's timing)."""

    def __init__(self) -> None:
        self.deltas: list[np.ndarray] = []

    def disturb(self, delta_lvlh: np.ndarray) -> None:
        self.deltas.append(np.array(delta_lvlh))


def _disturbed(fault: dict, ticks: int) -> tuple[FaultInjector, list[np.ndarray]]:
    """Run the injector over ``ticks`` ticks of 0.1 s; the per-tick deltas (zeros when none)."""
    sc = _scenario({"spacecraft": 2, "kind": "state_disturbance", **fault})
    truth = _Recorder()
    inj = _injector(sc, truth)
    out = []
    for k in range(ticks):
        t = k * sc.rates.dt_s
        before = len(truth.deltas)
        inj.update(t)
        inj.disturb(t)
        out.append(truth.deltas[-1] if len(truth.deltas) > before else np.zeros((2, 6)))
    return inj, out


def test_state_disturbance_bias_jumps_once_by_its_magnitudes() -> None:
    inj, deltas = _disturbed({"start_s": 1.0, "magnitude": 3.0, "velocity_mps": 0.02}, 30)
    moved = [k for k, d in enumerate(deltas) if np.any(d)]
    assert moved == [10]  # the tick of start_s only
    d = deltas[10]
    assert np.all(d[0] == 0.0)  # only spacecraft 2
    assert np.linalg.norm(d[1, :3]) == pytest.approx(3.0, rel=1e-12)
    assert np.linalg.norm(d[1, 3:]) == pytest.approx(0.02, rel=1e-12)
    assert d[1, :3].tolist() == inj.detail[0]["delta_r_lvlh_m"]


def test_state_disturbance_bias_over_an_interval_is_spread_evenly() -> None:
    _, deltas = _disturbed({"start_s": 1.0, "end_s": 3.0, "magnitude": 2.0}, 50)
    moved = [k for k, d in enumerate(deltas) if np.any(d)]
    assert moved == list(range(10, 30))  # the ticks of [1 s, 3 s)
    total = np.sum(deltas, axis=0)[1]
    assert np.linalg.norm(total[:3]) == pytest.approx(2.0, rel=1e-12)
    assert np.all(total[3:] == 0.0)


def test_state_disturbance_noise_walks_with_sqrt_time_and_repeats_from_the_seed() -> None:
    fault = {"start_s": 0.0, "end_s": 400.0, "magnitude": 0.5, "velocity_mps": 0.001,
             "disturbance": "noise"}
    _, deltas = _disturbed(fault, 4000)
    steps = np.array([d[1] for d in deltas])
    # per tick, per axis: 1σ = magnitude·√dt; 12,000 draws give the σ to about 1%
    assert steps[:, :3].std() == pytest.approx(0.5 * math.sqrt(0.1), rel=0.03)
    assert steps[:, 3:].std() == pytest.approx(0.001 * math.sqrt(0.1), rel=0.03)
    _, again = _disturbed(fault, 50)
    assert all(np.array_equal(a, b) for a, b in zip(again, deltas[:50], strict=True))


def test_the_truth_takes_a_disturbance_in_lvlh_exactly() -> None:
    chief = circular_chief_eci(500e3, math.radians(51.6))
    rel = np.array([[10.0, 0.0, 5.0, 0.0, -0.02, 0.0], [0.0, 20.0, 0.0, 0.01, 0.0, 0.0]])
    truth = RelativeTruth(chief, rel, energy_match=False, compiled=False)
    delta = np.zeros((2, 6))
    delta[1] = [1.0, -2.0, 0.5, 0.003, 0.0, -0.001]
    truth.disturb(delta)
    assert np.allclose(truth.rel_lvlh(), rel + delta, atol=1e-9)


@pytest.mark.parametrize("fault, says", [
    ({"magnitude": -1.0}, r"in \[0, 1000\]"),
    ({"magnitude": 0.0, "velocity_mps": 0.0}, "not both 0"),
    ({"magnitude": 1.0, "velocity_mps": -0.1}, r"\[0, 10\]"),
    ({"magnitude": 2e3}, "got 2000.0"),
    ({}, "needs a magnitude"),
    ({"magnitude": 1.0, "disturbance": "wobble"}, "disturbance"),
])
def test_a_bad_state_disturbance_is_refused(fault: dict, says: str) -> None:
    with pytest.raises(ValueError, match=says):
        _scenario({"spacecraft": 1, "kind": "state_disturbance", "start_s": 5.0, **fault})


def test_velocity_is_refused_on_other_kinds() -> None:
    with pytest.raises(ValueError, match="state_disturbance only"):
        _scenario({"spacecraft": 1, "kind": "thruster_bias", "start_s": 5.0, "magnitude": 0.1,
                   "velocity_mps": 0.1})
