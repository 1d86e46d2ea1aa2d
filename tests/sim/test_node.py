"""The sim node (sim/node.py) on a real in-process Bus, messages fed to its handlers: commands
stale, from the future or forged are refused and counted and never leave an actuator running, a
wheel torque times out when the flight computer stops commanding, and in the lockstep a
participant lost and back is named until it answers and TickDone announces only its sender's
own keys."""

from __future__ import annotations

import numpy as np

from interfaces.contracts import topics
from interfaces.contracts.messages import ThrustCommand, TickDone, WheelCommand
from interfaces.runtime.bus import Bus
from interfaces.runtime.transport import InprocNetwork
from sim.hardware import WHEEL_COMMAND_TIMEOUT_S
from sim.node import SimNode
from sim.units.thrusters import Thrusters
from sim.units.wheels import Wheels
from tests.conftest import small_scenario

M = "ld"


def _sim() -> SimNode:
    sc = small_scenario("cmd", observers={"count": 2})
    return SimNode(Bus("sim", "cmd", InprocNetwork().endpoint()), sc, participants=[])


def test_sim_refuses_stale_future_and_forged_commands() -> None:
    sim = _sim()
    sim._t_now = 100.0
    good = WheelCommand(sender="sc1", t_sim=100.0, spacecraft=1, torque_body_nm=[1e-3, 0, 0])
    wheels = sim.unit(Wheels).on_command
    sim._command(wheels, 0, good)
    assert sim.hw.tau_cmd[0, 0] == 1e-3 and sim.rejected_commands == 0
    for bad in (good.model_copy(update={"t_sim": 99.0, "torque_body_nm": [5e-3, 0, 0]}),  # stale
                good.model_copy(update={"t_sim": 101.0, "torque_body_nm": [5e-3, 0, 0]}),  # future
                good.model_copy(update={"spacecraft": 2, "torque_body_nm": [5e-3, 0, 0]}),
                good.model_copy(update={"sender": "sc2", "torque_body_nm": [5e-3, 0, 0]})):
        sim._command(wheels, 0, bad)
    assert sim.rejected_commands == 4 and sim.hw.tau_cmd[0, 0] == 1e-3
    replay = ThrustCommand(sender="sc1", t_sim=0.0, spacecraft=1, force_body_n=[0.02, 0, 0],
                           duration_s=3600.0)
    sim._command(sim.unit(Thrusters).on_command, 0, replay)
    assert sim.rejected_commands == 5 and not sim.hw.force_until.any()


def test_wheel_torque_times_out_when_the_flight_computer_stops_commanding() -> None:
    sim = _sim()
    hw, dt = sim.hw, 0.5
    hw.command_wheels(0, [1e-3, 0.0, 0.0], 0.0)
    t, h = 0.0, [hw.attitude.h[0, 0]]
    while t < WHEEL_COMMAND_TIMEOUT_S + 2.0:
        hw.step(t, dt)
        t += dt
        h.append(hw.attitude.h[0, 0])
    dh = np.diff(h)
    n_on = int(round(WHEEL_COMMAND_TIMEOUT_S / dt))
    assert np.allclose(dh[:n_on], -1e-3 * dt) and np.all(dh[n_on:] == 0.0)


def test_the_sim_names_a_rejoined_participant_until_it_answers() -> None:
    sc = small_scenario("ld", observers={"count": 2})
    sim = SimNode(Bus("sim", M, InprocNetwork().endpoint()), sc, participants=["sc1", "sc2"])
    for alive in (True, False, True):  # joined, lost, back
        sim.on_liveness("sc1", alive)
    sim.on_liveness("sc2", True)
    assert sim.lockstep.rejoining == {"sc1"}
    assert sim.lockstep.open_tick(4) == ["sc1"]
    sim._on_done(0, TickDone(sender="sc1", t_sim=2.0, k=4, published={}))
    assert sim.lockstep.rejoining == set()
    assert [e[0] for e in sim.lockstep.events["sc1"]] == ["lost", "rejoined"]


def test_tick_done_announces_only_the_senders_own_keys() -> None:
    sc = small_scenario("ld", observers={"count": 2})
    sim = SimNode(Bus("sim", M, InprocNetwork().endpoint()), sc, participants=["sc1", "sc2"])
    sim.lockstep.open_tick(4)
    own, foreign = topics.key(M, "sc1", "nav", "estimate"), topics.key(M, "sc2", "nav", "estimate")
    sim._on_done(0, TickDone(sender="sc1", t_sim=2.0, k=4, published={own: 9, foreign: 10**9}))
    sim._on_done(1, TickDone(sender="sc2", t_sim=2.0, k=3, published={foreign: 5}))  # old tick
    assert sim.lockstep.answers == {"sc1": {own: 9}}
