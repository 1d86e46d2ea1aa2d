"""The observers' GNC hardware in the sim: thrusters, reaction wheels and rigid-body attitude, for
all observers at once (the attitude sensors that read it: ``sim/units/attitude_sensors.py``).

Commands arrive from the flight software (``ThrustCommand``, ``WheelCommand``) and are held:
a thrust command is realised once, when it arrives, over its whole duration — the thrusters
fire it as pulse-width-modulated impulses, so the minimum impulse bit and the per-pulse noise
apply to the command's impulse, not to each tick — and the resulting average force is applied
until the duration ends; a wheel torque is held until the next command, at most
``WHEEL_COMMAND_TIMEOUT_S``.  Every random draw comes
from per-spacecraft, per-device generators of the scenario seed.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from gnc import quat
from interfaces.contracts.rng import stream
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S
from sim import kernels
from sim.actuators import ThrusterBank, WheelArray
from sim.attitude import AttitudeTruth

WHEEL_COMMAND_TIMEOUT_S = 1.0
"""A wheel torque not refreshed for this long is dropped to zero (a flight computer that stops
commanding must not leave the wheels spinning the body up), s."""


def initial_attitudes(scenario: Scenario, r_eci_lvlh: Rotation) -> tuple[np.ndarray, np.ndarray]:
    """Initial R_eci_body quaternions (N, 4) and body rates (N, 3, rad/s) of the observers:
    uniformly random (seeded per spacecraft) or aligned with LVLH, plus a seeded tumble."""
    obs = scenario.observers
    q, w = [], []
    for i in range(1, obs.count + 1):
        rng = stream(scenario.seed, "attitude_init", i)
        r = (Rotation.random(random_state=rng) if obs.initial_attitude == "random"
             else r_eci_lvlh)
        q.append(r.as_quat())
        w.append(math.radians(obs.tumble_rate_dps) * rng.standard_normal(3))
    return np.array(q), np.array(w)


class ObserverHardware:
    """Thrusters, wheels and attitude truth of all observers.  ``compiled``:
    the frame and thrust glue of the 10 Hz tick run on :mod:`sim.kernels` (the same bits as the
    numpy reference, which ``compiled=False`` runs)."""

    def __init__(self, scenario: Scenario, r_eci_lvlh: Rotation, compiled: bool = True) -> None:
        sc = scenario
        self.compiled = compiled
        n = sc.observers.count
        ids = range(1, n + 1)
        act = sc.actuators
        self.n = n
        self.mass_kg = sc.observers.mass_kg
        q0, w0 = initial_attitudes(sc, r_eci_lvlh)
        self.attitude = AttitudeTruth(q0, w0, np.diag(sc.observers.inertia_kg_m2), np.zeros((n, 3)))
        self.thrusters = [ThrusterBank(act.thruster_max_force_n, act.thruster_min_impulse_ns,
                                       act.thruster_noise_frac, [stream(sc.seed, "thruster", i)])
                          for i in ids]
        self.wheels = WheelArray(n, act.wheel_max_torque_nm, act.wheel_max_momentum_nms,
                                 compiled=compiled)
        self.force_body = np.zeros((n, 3))
        self.force_until = np.zeros(n)
        self.force_bias_body = np.zeros((n, 3))
        """Continuous force in body axes, N (fault hook: ``thruster_bias``, a leaking valve)."""
        self.tau_cmd = np.zeros((n, 3))
        self.tau_until = np.zeros(n)
        self.dv_mps = np.zeros(n)

    # --- commands -----------------------------------------------------------------------------

    def command_thrust(self, index: int, force_body_n: list[float], duration_s: float,
                       t_s: float) -> None:
        """Realise a thrust command of observer ``index`` (0-based) from ``t_s`` for
        ``duration_s``; it replaces any command still running."""
        f = self.thrusters[index].fire(np.array([force_body_n]), duration_s)
        self.force_body[index] = f[0]
        self.force_until[index] = t_s + duration_s

    def command_wheels(self, index: int, torque_body_nm: list[float], t_s: float) -> None:
        """Hold a wheel torque of observer ``index`` from ``t_s`` (until the next command or the
        timeout)."""
        self.tau_cmd[index] = torque_body_nm
        self.tau_until[index] = t_s + WHEEL_COMMAND_TIMEOUT_S

    # --- one tick -----------------------------------------------------------------------------

    def accel_lvlh(self, t_s: float, q_lvlh_eci: np.ndarray) -> np.ndarray:
        """Thrust acceleration in LVLH over the tick starting at ``t_s`` (N, 3), m/s², given the
        true ECI -> LVLH rotation as a quaternion (4,)."""
        q_lvlh_body = self.q_lvlh_body(q_lvlh_eci)
        if self.compiled:
            return kernels.thrust_accel_lvlh(q_lvlh_body, self.force_body, self.force_until,
                                             self.force_bias_body, float(t_s), self.mass_kg)
        active = (t_s < self.force_until - TIME_TOL_S)[:, None]
        f = np.where(active, self.force_body, 0.0) + self.force_bias_body
        out: np.ndarray = quat.rotate(q_lvlh_body, f) / self.mass_kg
        return out

    def step(self, t_s: float, dt_s: float) -> None:
        """Advance the attitude (wheel torques held) and the Δv bookkeeping by one tick."""
        # Propellant proxy: commanded and leaked force are spent separately (a leak on one
        # thruster of an axis is not refunded by firing the opposite one).
        if self.compiled:
            held = kernels.spend_and_hold(self.dv_mps, self.force_body, self.force_until,
                                          self.force_bias_body, self.tau_cmd, self.tau_until,
                                          float(t_s), float(dt_s), self.mass_kg)
        else:
            active = (t_s < self.force_until - TIME_TOL_S)[:, None]
            spent = np.abs(np.where(active, self.force_body, 0.0)) + np.abs(self.force_bias_body)
            self.dv_mps += spent.sum(axis=1) * dt_s / self.mass_kg
            held = np.where((t_s < self.tau_until - TIME_TOL_S)[:, None], self.tau_cmd, 0.0)
        tau = self.wheels.realise(held, self.attitude.h, dt_s)
        self.attitude.step(dt_s, tau)

    def q_lvlh_body(self, q_lvlh_eci: np.ndarray) -> np.ndarray:
        """True attitudes with respect to LVLH (N, 4), scalar last, given the true ECI -> LVLH
        rotation as a quaternion (4,)."""
        if self.compiled:
            return kernels.lvlh_attitudes(np.asarray(q_lvlh_eci, dtype=float),
                                          self.attitude.q)
        return quat.mul(np.broadcast_to(q_lvlh_eci, (self.n, 4)), self.attitude.q)
