"""Fault injection into the hardware stand-in: the scenario's ``[[faults]]`` switched on at
``start_s`` and off at ``end_s`` (``faults/schedule.py``; docs/contracts.md, "Scenario TOML":
kinds and magnitudes).  The sim hands its units to the injector.

The sim's kinds act on the truth, as a failing unit would:

* ``thruster_bias``: a continuous force of ``magnitude`` × the maximum thrust per axis, in a
  body direction drawn from the seed (a leaking or stuck-open valve: it acts whether or not the
  thrusters fire, and it is counted in the Δv spent).
* ``pointing_actuator``: a wheel torque bias perpendicular to the boresight, sized so that the
  nominal attitude loop settles ``magnitude`` degrees off its target: with the small-error
  closed loop ``J δθ̈ + J kd δθ̇ + J (kp/2) δθ = τ_bias`` (``gnc.attitude_gains``),
  ``τ_bias = J kp θ / 2`` per axis.  The attitude estimate sees the error; the loop cannot
  remove it.
* ``camera_degradation``: every precision scaled by β = ``magnitude`` (Eq. 21).
* ``camera_misalignment``: the camera boresight rotated by ``magnitude`` degrees about a body
  axis perpendicular to it, drawn from the seed; the attitude loop does not know.
* ``nav_sensor_bias``: the relative-navigation position measurement offset by ``magnitude`` m in
  an LVLH direction drawn from the seed.
* ``camera_calibration`` (common mode, ``spacecraft = 0``): every observer's precisions scaled
  by ``magnitude``, as if the true variance coefficient were k / ``magnitude`` while the ground
  models k: no single observer explains it.
* ``state_disturbance`` (Sec. III.G's actuator fault): the true relative position moved by
  ``magnitude`` m and velocity by ``velocity_mps`` m/s, in LVLH.  A ``bias`` (the default)
  moves them along two directions drawn from the seed: all at once on the tick of ``start_s``
  without ``end_s``, or spread evenly over the ticks of [start_s, end_s) (a drift).  A
  ``noise`` draws a Gaussian offset per axis from the fault's own stream: once, with 1σ
  ``magnitude`` and ``velocity_mps``, without ``end_s``; on every tick of [start_s, end_s),
  scaled by √(dt / 1 s), so that the 1σ of the walk after 1 s is ``magnitude`` and
  ``velocity_mps`` and grows as √(duration).  Nav and guidance see the new state through the
  sensors, as they would after an unplanned impulse, and steer back to the plan.

The link kinds (``link_loss``, ``packet_loss``) act in every node's channel stage
(``links/faults.py``) and ``faulty_data`` in the faulty spacecraft's software
(``faults/software.py``); the injector switches them too, so that the truth of every fault is
archived.

Every switch is returned as a :class:`FaultSwitch` (for the ``FaultEvent`` truth message).
Random directions come from ``interfaces.contracts.rng.stream(seed, "fault", k)`` for the k-th
fault.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from faults.schedule import HARDWARE_KINDS, switched_on
from gnc.attitude_gains import gains_for
from interfaces.contracts.rng import stream
from interfaces.contracts.scenario import Fault, Scenario


class Wheels(Protocol):
    torque_bias_nm: np.ndarray
    """per observer, body axes, N·m"""


class Hardware(Protocol):
    """The sim's actuators as the faults reach them (``sim/hardware.py``)."""

    force_bias_body: np.ndarray
    """per observer, body axes, N"""

    @property
    def wheels(self) -> Wheels: ...


class Disturbable(Protocol):
    """The sim's truth as a state disturbance reaches it (``sim/dynamics.py``)."""

    def disturb(self, delta_lvlh: np.ndarray) -> None:
        """Add ``delta_lvlh`` (N, 6: m, m/s, LVLH) to the observers' relative states."""
        ...


class Cameras(Protocol):
    """The sim's cameras as the faults reach them (``sim/camera.py``)."""

    beta: np.ndarray
    misalignment: np.ndarray


class RelNav(Protocol):
    """One relative-navigation sensor (``sim/sensors.py``)."""

    bias_m: np.ndarray


@dataclass(frozen=True)
class FaultSwitch:
    """A fault turned on or off at ``t_s`` (s); ``detail`` holds the realised parameters
    (directions, torques) for the archive."""

    index: int
    fault: Fault
    active: bool
    t_s: float
    detail: dict[str, list[float] | float]


def _random_unit(rng: np.random.Generator, perpendicular_to: np.ndarray | None = None
                 ) -> np.ndarray:
    """A random unit vector (uniform on the sphere, or on the circle perpendicular to the unit
    vector ``perpendicular_to``)."""
    while True:
        v = rng.standard_normal(3)
        if perpendicular_to is not None:
            v -= (v @ perpendicular_to) * perpendicular_to
        norm = float(np.linalg.norm(v))
        if norm > 1e-6:
            return v / norm


def _axis_angle_quat(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """Quaternion (scalar last) of a rotation by ``angle_rad`` about unit ``axis``."""
    return np.concatenate([axis * math.sin(angle_rad / 2.0), [math.cos(angle_rad / 2.0)]])


@dataclass
class FaultInjector:
    """Switches the scenario's faults on the sim's hardware, cameras and relnav sensors.

    Attributes:
        scenario: the mission (faults, actuator limits, attitude settling time, inertia).
        hardware, cameras, relnav: the units the faults act on.
        detail: per fault, the realised parameters (drawn once, at construction).
    """

    scenario: Scenario
    hardware: Hardware
    cameras: Cameras
    relnav: list[RelNav]
    truth: Disturbable | None = None
    """the truth a ``state_disturbance`` moves (a scenario with one needs it)"""
    detail: list[dict[str, list[float] | float]] = field(init=False)

    def __post_init__(self) -> None:
        self._active = [False] * len(self.scenario.faults)
        self._pending: set[int] = set()  # one-shot disturbances switched on, not yet applied
        self.detail = [self._realise(k, f) for k, f in enumerate(self.scenario.faults)]
        self._noise = {k: stream(self.scenario.seed, "fault-noise", k)
                       for k, f in enumerate(self.scenario.faults)
                       if f.kind == "state_disturbance" and f.disturbance == "noise"}
        if self.truth is None and any(f.kind == "state_disturbance"
                                      for f in self.scenario.faults):
            raise ValueError("a state_disturbance fault needs the truth to act on")

    def _realise(self, k: int, f: Fault) -> dict[str, list[float] | float]:
        """The concrete parameters of fault k (directions drawn from its own stream)."""
        sc = self.scenario
        rng = stream(sc.seed, "fault", k)
        boresight = np.array(sc.attitude.boresight_body, dtype=float)
        boresight /= np.linalg.norm(boresight)
        mag = float(f.magnitude or 0.0)
        if f.kind == "thruster_bias":
            d = _random_unit(rng)
            return {"direction_body": d.tolist(),
                    "force_body_n": (mag * sc.actuators.thruster_max_force_n * d).tolist()}
        if f.kind == "pointing_actuator":
            axis = _random_unit(rng, boresight)
            kp = gains_for(sc.attitude.settling_time_s).kp
            torque = np.array(sc.observers.inertia_kg_m2) * axis * kp * math.radians(mag) / 2.0
            return {"axis_body": axis.tolist(), "torque_bias_nm": torque.tolist()}
        if f.kind == "camera_misalignment":
            axis = _random_unit(rng, boresight)
            return {"axis_body": axis.tolist(),
                    "rotation_xyzw": _axis_angle_quat(axis, math.radians(mag)).tolist()}
        if f.kind == "nav_sensor_bias":
            d = _random_unit(rng)
            return {"direction_lvlh": d.tolist(), "bias_lvlh_m": (mag * d).tolist()}
        if f.kind == "state_disturbance":
            return self._realise_disturbance(f, rng)
        return {"magnitude": mag} if f.magnitude is not None else {}

    def _realise_disturbance(self, f: Fault, rng: np.random.Generator
                             ) -> dict[str, list[float] | float]:
        """A bias's total offset (directions from the seed) or a noise's 1σ, and the ticks it
        is spread over (1: at once)."""
        dt = self.scenario.rates.dt_s
        ticks = 1 if f.end_s is None else max(1, round((f.end_s - f.start_s) / dt))
        dv = f.velocity_mps or 0.0
        if f.disturbance == "noise":
            return {"sigma_m": float(f.magnitude or 0.0), "sigma_mps": dv, "ticks": ticks}
        dr_dir, dv_dir = _random_unit(rng), _random_unit(rng)
        return {"delta_r_lvlh_m": (float(f.magnitude or 0.0) * dr_dir).tolist(),
                "delta_v_lvlh_mps": (dv * dv_dir).tolist(), "ticks": ticks}

    def _disturbance(self, k: int, f: Fault) -> np.ndarray:
        """Fault k's offset (6,: m, m/s, LVLH) on one tick it acts."""
        d = self.detail[k]
        if f.disturbance != "noise":
            total = np.concatenate([np.array(d["delta_r_lvlh_m"]), np.array(d["delta_v_lvlh_mps"])])
            return total / float(d["ticks"])  # type: ignore[arg-type]
        scale = 1.0 if f.end_s is None else math.sqrt(self.scenario.rates.dt_s)
        sigma = np.repeat([float(d["sigma_m"]), float(d["sigma_mps"])], 3)  # type: ignore[arg-type]
        return self._noise[k].standard_normal(6) * sigma * scale

    def disturb(self, t_s: float) -> None:
        """Move the truth by the state disturbances acting on the tick at ``t_s`` (call after
        :meth:`update` for the same tick): a one-shot one on its switch-on tick, an interval's
        on each of its ticks."""
        delta = None
        for k, f in enumerate(self.scenario.faults):
            if f.kind != "state_disturbance" or not self._active[k]:
                continue
            if f.end_s is None and k not in self._pending:
                continue
            self._pending.discard(k)
            if delta is None:
                delta = np.zeros((self.scenario.observers.count, 6))
            delta[f.spacecraft - 1] += self._disturbance(k, f)
        if delta is not None:
            assert self.truth is not None  # refused at construction otherwise
            self.truth.disturb(delta)

    def update(self, t_s: float) -> list[FaultSwitch]:
        """Apply every fault whose state changes at ``t_s`` (on at start_s ≤ t, off at end_s ≤ t);
        returns the switches."""
        out = []
        for k, f in enumerate(self.scenario.faults):
            on = switched_on(f, t_s)
            if on != self._active[k]:
                self._active[k] = on
                if f.kind in HARDWARE_KINDS:
                    self._apply(k, f, on)
                if f.kind == "state_disturbance" and on:
                    self._pending.add(k)
                out.append(FaultSwitch(k, f, on, t_s, self.detail[k]))
        return out

    def _apply(self, k: int, f: Fault, on: bool) -> None:
        i = f.spacecraft - 1
        d = self.detail[k]
        if f.kind == "thruster_bias":
            self.hardware.force_bias_body[i] = np.array(d["force_body_n"]) if on else 0.0
        elif f.kind == "pointing_actuator":
            bias = self.hardware.wheels.torque_bias_nm
            bias[i] = np.array(d["torque_bias_nm"]) if on else 0.0
            self.hardware.wheels.torque_bias_nm = bias
        elif f.kind == "camera_degradation":
            self.cameras.beta[i] = float(f.magnitude or 1.0) if on else 1.0
        elif f.kind == "camera_calibration":
            self.cameras.beta[:] = float(f.magnitude or 1.0) if on else 1.0
        elif f.kind == "camera_misalignment":
            self.cameras.misalignment[i] = np.array(d["rotation_xyzw"]) if on \
                else np.array([0.0, 0.0, 0.0, 1.0])
        elif f.kind == "nav_sensor_bias":
            self.relnav[i].bias_m = np.array(d["bias_lvlh_m"]) if on else np.zeros(3)
