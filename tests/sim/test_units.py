"""The sim's hardware units (sim/units) in a real sim node on an in-process Bus: each publishes
only on the ticks it is due, in the order of the task list; what a sensor unit publishes is
what its unit class measures with the same seeded generators; the commands reach their
actuator unit through the bus; a unit publishes only what it declares."""

from __future__ import annotations

import numpy as np
import pytest

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import (
    AttitudeMeasurement,
    CameraImage,
    Message,
    RelNavMeasurement,
    ThrustCommand,
    WheelCommand,
)
from interfaces.contracts.rng import stream
from interfaces.runtime.bus import Bus
from interfaces.runtime.transport import InprocNetwork
from sim.camera import TruthCameras
from sim.node import SimNode
from sim.sensors import Gyro, RelNavSensor, StarTracker
from sim.units import UNITS
from sim.units.attitude_sensors import AttitudeSensors
from sim.units.camera import Camera
from sim.units.relnav import RelNav
from sim.units.thrusters import Thrusters
from sim.units.unit import Unit
from sim.units.wheels import Wheels
from tests.conftest import small_scenario

M = "units"


def _sim(net: InprocNetwork | None = None) -> SimNode:
    """A sim of 3 observers at 2 Hz (ω_mid 1 Hz: every other tick), star tracker at 1 Hz."""
    net = net or InprocNetwork()
    return SimNode(Bus(topics.SIM, M, net.endpoint()), small_scenario(M), participants=[])


def _kept(sim: SimNode) -> list[tuple[str, Message]]:
    """The list every message the sim publishes from now on is appended to, (key, message)."""
    out: list[tuple[str, Message]] = []
    send = sim.bus.publish

    def keep(key: str, msg: Message, announce: bool = True) -> None:
        out.append((key, msg))
        send(key, msg, announce)

    sim.bus.publish = keep  # type: ignore[method-assign]
    return out


def _of(kept: list[tuple[str, Message]], kind: type[Message]) -> list[Message]:
    return [m for _, m in kept if isinstance(m, kind)]


def test_each_unit_publishes_only_on_the_ticks_it_is_due_in_task_list_order() -> None:
    sim = _sim()
    kept = _kept(sim)
    dt = sim.scenario.rates.dt_s
    for k in range(5):
        kept.clear()
        sim._publish_hardware(k, k * dt)
        sensors = [cat.ATTITUDE_SENSORS] + ([cat.CAMERA_IMAGE, cat.RELNAV] if k % 2 == 0 else [])
        want = [cat.TRUTH.key(M)] + [t.key(M, topics.sc_node(i)) for t in sensors
                                     for i in (1, 2, 3)]
        assert [key for key, _ in kept] == want, k
    assert [u.due(k) for u in sim.units for k in (0, 1, 2)] == [
        True, True, True,  # attitude sensors: every tick
        True, False, True, True, False, True,  # camera, relnav: ω_mid
        True, True, True, True, True, True]  # actuators: no outputs, nothing to step


def test_attitude_sensors_publish_the_gyro_and_star_tracker_of_their_streams() -> None:
    sim = _sim()
    kept = _kept(sim)
    sc, dt = sim.scenario, sim.scenario.rates.dt_s
    sen, ids = sc.sensors, sim.ids
    gyro = Gyro([stream(sc.seed, "gyro", i) for i in ids], sen.gyro_arw_rad_rts,
                sen.gyro_bias_rw_rad_s15, sen.gyro_bias_sigma_radps)
    st = StarTracker([stream(sc.seed, "star_tracker", i) for i in ids],
                     sen.star_tracker_cross_arcsec, sen.star_tracker_roll_arcsec,
                     boresight_axis=int(np.argmax(np.abs(sc.attitude.boresight_body))),
                     rate_hz=sen.star_tracker_hz)
    att, fixes = sim.hw.attitude, []
    for k in (0, 1):  # a fix at t = 0, none half a second later
        kept.clear()
        sim._publish_hardware(k, k * dt)
        rates = gyro.measure(att.mean_rate, dt)
        fix = st.measure(k * dt, att.r_eci_body())
        fixes.append(fix is not None)
        msgs = _of(kept, AttitudeMeasurement)
        assert [m.spacecraft for m in msgs] == ids
        assert [m.gyro_radps for m in msgs] == rates.tolist()
        assert [m.star_tracker for m in msgs] == ([None] * 3 if fix is None else fix.tolist())
    assert fixes == [True, False]
    unit = sim.unit(AttitudeSensors)
    assert msgs[0].st_sigma_cross_rad == unit.st_sigma_rad[0] == pytest.approx(
        np.radians(sen.star_tracker_cross_arcsec / 3600.0))


def test_relnav_publishes_its_sensors_measurement_of_the_truth_bias_included() -> None:
    sim = _sim()
    kept = _kept(sim)
    sc = sim.scenario
    twins = [RelNavSensor(sc.sensors.relnav_sigma_r_m, sc.sensors.relnav_sigma_v_mps,
                          stream(sc.seed, "relnav", i)) for i in sim.ids]
    sim.unit(RelNav).sensors[1].bias_m = twins[1].bias_m = np.array([3.0, 0.0, -1.0])
    rel = sim.truth.rel_lvlh()
    sim._publish_hardware(0, 0.0)
    msgs = _of(kept, RelNavMeasurement)
    for m, twin, truth in zip(msgs, twins, rel, strict=True):
        r, v = twin.measure(truth[:3], truth[3:])
        assert (m.r_m, m.v_mps) == (r.tolist(), v.tolist())
        assert (m.sigma_r_m, m.sigma_v_mps) == (twin.sigma_r_m, twin.sigma_v_mps)
    assert np.linalg.norm(np.array(msgs[1].r_m) - rel[1, :3]) > 2.0


def test_camera_publishes_the_images_its_cameras_take_of_the_true_pose() -> None:
    sim = _sim()
    kept = _kept(sim)
    sc, k = sim.scenario, sim.constants
    twin = TruthCameras(k.poi_pos, k.poi_normal, k.camera, np.array(sc.attitude.boresight_body),
                        sc.camera.noise_frac, [stream(sc.seed, "camera", i) for i in sim.ids])
    unit = sim.unit(Camera)
    unit.cameras.beta[2] = twin.beta[2] = 0.5  # the fault hook reaches the published image
    q = sim.hw.q_lvlh_body(sim._q_lvlh_eci())
    images = twin.images(sim.truth.rel_lvlh()[:, :3], q)
    sim._publish_hardware(0, 0.0)
    msgs = _of(kept, CameraImage)
    assert [m.spacecraft for m in msgs] == sim.ids
    assert [(m.poi.tolist(), m.precision.tolist()) for m in msgs] == [
        (img.poi.tolist(), img.precision.tolist()) for img in images]


def test_commands_reach_their_actuator_unit_through_the_bus() -> None:
    net = InprocNetwork()
    sim = _sim(net)
    sc1 = Bus("sc1", M, net.endpoint())
    sc1.publish(cat.THRUST.key(M, "sc1"), ThrustCommand(
        sender="sc1", t_sim=0.0, spacecraft=1, force_body_n=[0.01, 0.0, 0.0], duration_s=2.0))
    sc1.publish(cat.WHEELS.key(M, "sc1"), WheelCommand(
        sender="sc1", t_sim=0.0, spacecraft=1, torque_body_nm=[0.0, 2e-4, 0.0]))
    sim.bus.dispatch(0.0, include_now=True)
    hw = sim.hw
    assert hw.force_until.tolist() == [2.0, 0.0, 0.0] and hw.force_body[0, 0] > 0.0
    assert hw.tau_cmd[0].tolist() == [0.0, 2e-4, 0.0] and not hw.tau_cmd[1:].any()
    assert sim.rejected_commands == 0


def test_the_sim_declares_what_its_units_publish_and_take() -> None:
    assert [u.NAME for u in UNITS] == [
        "attitude_sensors", "camera", "relnav", "thrusters", "wheels"]
    outputs = {t for u in UNITS for t in u.OUTPUTS}
    assert outputs == {cat.ATTITUDE_SENSORS, cat.CAMERA_IMAGE, cat.RELNAV}
    assert outputs < set(SimNode.PUBLISHES)
    assert {c.topic for u in (Thrusters, Wheels) for c in u.COMMANDS} == {cat.THRUST, cat.WHEELS}
    assert {cat.THRUST, cat.WHEELS} < set(SimNode.SUBSCRIBES)


def test_a_unit_publishes_only_its_declared_hardware_topics() -> None:
    sim = _sim()
    relnav = sim.unit(RelNav)
    image = CameraImage.of_arrays(topics.SIM, 0.0, 1, np.array([0]), np.array([1.0]))
    with pytest.raises(TypeError, match="does not publish"):
        relnav.publish(cat.CAMERA_IMAGE, 0, image)
    with pytest.raises(TypeError, match="not a hardware topic"):
        type("Clock", (Unit,), {"NAME": "clock", "OUTPUTS": (cat.TICK,)})
