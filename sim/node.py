"""The sim process: time master and hardware stand-in.

Each tick k (t = k·dt, dt = 1/ω_high): publish the truth and the sensors due at t, publish
Tick k announcing them (and what the nodes published in tick k-1), wait for every participant's
TickDone(k) — lockstep — or until the per-tick timeout (the missing answer is logged and its
last command held) or, in real-time mode, until the next tick is due on the wall clock; then
apply the commands (thrust, wheel torques: ``sim.hardware``) and integrate the truth (orbit and
attitude) to t + dt.  The hardware is a task list of units (``sim/units``): each publishes its
sensor's measurements on the ticks it is due, or takes its actuator's commands.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import ClassVar, TypeVar

import numpy as np
from scipy.spatial.transform import Rotation

from faults.hardware import FaultInjector
from gnc import quat
from gnc.hcw import pro_state
from gnc.mission import MissionConstants
from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.catalogue import Topic
from interfaces.contracts.messages import FaultEvent, SimStatus, Tick, TickDone, TruthState
from interfaces.contracts.scenario import Scenario
from interfaces.runtime.bus import Bus
from interfaces.runtime.kernels import compile_kernels
from interfaces.runtime.recent import recover
from sim.dynamics import RelativeTruth, circular_chief_eci, lvlh_basis
from sim.hardware import ObserverHardware
from sim.lockstep import LinkAwait, Lockstep
from sim.pacing import Pacer
from sim.units import UNITS
from sim.units.camera import Camera
from sim.units.relnav import RelNav
from sim.units.unit import Sensed, SpacecraftCommand, Unit, UnitContext

U = TypeVar("U", bound=Unit)


def initial_states(scenario: Scenario, n: float) -> np.ndarray:
    """Initial LVLH relative states (N, 6) of the observers: on their scenario PROs, or just
    released from the target (``observers.start = "deploy"``: at ``deploy_radius_m`` moving
    outward at ``deploy_speed_mps``, directions fanned evenly in the along-track/cross-track
    plane); ``n``: the target's mean motion, rad/s."""
    obs = scenario.observers
    if obs.start == "deploy":
        theta = 2.0 * np.pi * np.arange(obs.count) / obs.count
        d = np.stack([np.zeros(obs.count), np.cos(theta), np.sin(theta)], axis=1)
        return np.hstack([obs.deploy_radius_m * d, obs.deploy_speed_mps * d])
    return np.array([pro_state(n, *obs.pro(i)) for i in range(1, obs.count + 1)])


@dataclass(frozen=True)
class NodeInput:
    """A sim subscription: ``topic`` on the key of each lockstep participant, to method
    ``handler``, called with the participant's index and the message; ``immediate``: handled on
    arrival (the lockstep's answers), not queued to the tick.  The hardware's commands are the
    units' (``Unit.COMMANDS``)."""

    topic: Topic
    handler: str
    immediate: bool = False


@dataclass(eq=False)
class SimNode:
    """The sim's side of the bus: what it publishes, and its inputs, wired from these
    declarations (``INPUTS``, and its units' ``OUTPUTS`` and ``COMMANDS``) as an app's are; the
    participants' answers and liveness are kept by its ``lockstep`` (``sim.lockstep``)."""

    PUBLISHES: ClassVar[tuple[Topic, ...]] = (
        cat.TICK, cat.SIM_STATUS, cat.TRUTH, cat.FAULT_EVENTS,
        *(t for u in UNITS for t in u.OUTPUTS))
    INPUTS: ClassVar[tuple[NodeInput, ...]] = (
        NodeInput(cat.TICK_DONE, "_on_done", immediate=True),
    )
    SUBSCRIBES: ClassVar[tuple[Topic, ...]] = (
        *(i.topic for i in INPUTS), *(c.topic for u in UNITS for c in u.COMMANDS))

    bus: Bus
    scenario: Scenario
    participants: list[str]
    realtime_speed: float | None = None
    """``--realtime SPEED``: at most this many times real time (``sim/pacing.py``)"""
    hard_deadline: bool = False
    """with ``realtime_speed``: answers waited for only until the next tick is due"""
    hold_lost_s: float = 0.0
    """how long a lost participant is waited for before the next tick (its restart), wall s"""
    link_awaits: tuple[LinkAwait, ...] = ()
    """a rehearsal's link cuts and restorations, in time order (``LinkAwait``)"""
    log: logging.Logger = field(default_factory=lambda: logging.getLogger("insp.sim"))
    stop: threading.Event = field(default_factory=threading.Event)
    completed: bool = field(default=False, init=False)
    """whether every tick ran (False: stopped by ``stop`` before the end)"""

    def __post_init__(self) -> None:
        compile_kernels()  # loaded before the first tick (compiled if the cache lacks them)
        sc = self.scenario
        self.constants = MissionConstants.of(sc)
        chief = circular_chief_eci(
            sc.orbit.altitude_km * 1e3, np.radians(sc.orbit.inclination_deg),
            np.radians(sc.orbit.raan_deg), np.radians(sc.orbit.arg_latitude_deg))
        self.truth = RelativeTruth(
            chief, initial_states(sc, self.constants.n_rad_s), j2=sc.orbit.j2,
            energy_match=sc.observers.energy_match and sc.observers.start == "pro")
        self.ids = list(range(1, sc.observers.count + 1))
        self.hw = ObserverHardware(sc, Rotation.from_quat(quat.conj(self._q_lvlh_eci())))
        ctx = UnitContext(self.bus, sc, self.constants, self.hw, self.log)
        self.units = [unit(ctx) for unit in UNITS]
        """the task list: stepped in this order on the ticks each is due"""
        self.faults = FaultInjector(sc, self.hw, self.unit(Camera).cameras,
                                    self.unit(RelNav).sensors, self.truth)
        m = self.bus.mission
        self._keys = {"tick": cat.TICK.key(m), "status": cat.SIM_STATUS.key(m),
                      "truth": cat.TRUTH.key(m), "faults": cat.FAULT_EVENTS.key(m)}
        self.pacer = (Pacer(self.realtime_speed, self.hard_deadline, self.log)
                      if self.realtime_speed is not None else None)
        self.lockstep = Lockstep(self.participants, m, sc.n_ticks - 1, lambda: self._t_now,
                                 self.stop, self.log,
                                 realtime=self.pacer is not None and self.pacer.hard,
                                 hold_s=self.hold_lost_s)
        self.rejected_commands = 0
        self._t_now = 0.0
        self._q_now = np.array([0.0, 0.0, 0.0, 1.0])  # ECI -> LVLH now (set each tick)
        self._dt = sc.rates.dt_s
        self._wire()

    def unit(self, kind: type[U]) -> U:
        """The sim's unit of class ``kind``."""
        return next(u for u in self.units if isinstance(u, kind))

    def _wire(self) -> None:
        """Subscribe the declared inputs (``INPUTS``) on each participant's key, then each
        unit's commands (``Unit.COMMANDS``) on each observer's."""
        m = self.bus.mission
        for i in self.INPUTS:
            handler = getattr(self, i.handler)
            for index, node in enumerate(self.participants):
                self.bus.subscribe(i.topic.key(m, node), i.topic.type, partial(handler, index),
                                   immediate=i.immediate)
        for u in self.units:
            for c in u.COMMANDS:
                for index, sc_id in enumerate(self.ids):
                    self.bus.subscribe(c.topic.key(m, topics.sc_node(sc_id)), c.topic.type,
                                       partial(self._command, getattr(u, c.handler), index))

    # --- commands to the hardware ---------------------------------------------------------

    def _accept(self, index: int, msg: SpacecraftCommand) -> bool:
        """A command is applied only if it is of the current tick (a replayed, stale or
        future-dated one is refused) and names the spacecraft whose key it came on (the key
        space itself is the publisher's, enforced by the Bus and access control).  Refusals are
        counted and reported in SimStatus."""
        sc = self.ids[index]
        why = ("stale or future-dated" if abs(msg.t_sim - self._t_now) > 0.5 * self._dt
               else "names another spacecraft" if msg.spacecraft != sc or
               msg.sender != topics.sc_node(sc) else "")
        if why:
            self.rejected_commands += 1
            if self.rejected_commands <= 5 or self.rejected_commands % 100 == 0:
                self.log.warning("refused %s for sc%d at t=%.1f s (t_sim %.1f s): %s (#%d)",
                                 type(msg).__name__, sc, self._t_now, msg.t_sim, why,
                                 self.rejected_commands)
        return not why

    def _command(self, handler: Callable[[int, SpacecraftCommand], None], index: int,
                 msg: SpacecraftCommand) -> None:
        """A command of observer ``index`` to a unit: to its ``handler`` if accepted."""
        if self._accept(index, msg):
            handler(index, msg)

    def _q_lvlh_eci(self) -> np.ndarray:
        """Quaternion (scalar last) of the rotation taking ECI vectors into the true LVLH frame
        of the target now."""
        return quat.from_matrix(lvlh_basis(self.truth.chief_eci))

    # --- the lockstep (sim.lockstep) -------------------------------------------------------

    def _on_done(self, _index: int, msg: TickDone) -> None:
        """A participant's answer to the current tick (``Lockstep.on_done``)."""
        self.lockstep.on_done(msg)

    def on_liveness(self, node: str, alive: bool) -> None:
        """Liveliness handler (``Lockstep.on_liveness``): a participant lost or back."""
        self.lockstep.on_liveness(node, alive)

    def wait_for_participants(self, timeout_s: float) -> None:
        """Block until every participant has announced itself (Zenoh liveliness)."""
        self.lockstep.wait_for_participants(timeout_s)

    # --- the run --------------------------------------------------------------------------

    def run(self) -> bool:
        """Run all ticks; True if the run completed, False if it was stopped."""
        sc = self.scenario
        dt, n_ticks = sc.rates.dt_s, sc.n_ticks
        self._status("running", 0)
        expect: dict[str, int] = {}
        wall0 = time.monotonic()
        if self.pacer is not None:
            self.pacer.start()
        for k in range(n_ticks):
            if self.stop.is_set():
                self._status("aborted", k, "stopped by signal")
                return False
            t = self._t_now = k * dt
            if self.pacer is not None:
                self.pacer.wait(t)
            held_s = self.lockstep.hold_for_services()
            if self.stop.is_set():  # stopped while holding: this tick is not run
                self._status("aborted", k, "stopped by signal")
                return False
            if held_s and self.pacer is not None:
                self.pacer.slip(held_s)
            self._publish_hardware(k, t)
            expect.update(self.bus.published_since_last())
            tick = partial(Tick, sender=topics.SIM, t_sim=t, k=k, dt_s=dt, expect=expect,
                           final=k == n_ticks - 1)
            self.bus.publish(self._keys["tick"], tick(rejoin=self.lockstep.open_tick(k)),
                             announce=False)
            self.bus.flush_bundle()  # the hardware frames and the tick, as one
            deadline = (self.pacer.answer_deadline(t, dt, sc.sim.lockstep_timeout_s)
                        if self.pacer is not None
                        else time.monotonic() + sc.sim.lockstep_timeout_s)
            expect = self.lockstep.collect_answers(
                k, deadline, lambda back, tick=tick: self._send_again(tick, back),
                sc.sim.lockstep_timeout_s)
            if self.lockstep.held_s and self.pacer is not None:
                self.pacer.slip(self.lockstep.held_s)
            self._commands_in(expect, deadline)
            self.bus.dispatch(t, include_now=True)
            if k < n_ticks - 1:
                accel = self.hw.accel_lvlh(t, self._q_now)
                self.truth.step(dt, accel, substeps=sc.sim.substeps)
                self.hw.step(t, dt)
                if self.link_awaits:
                    self._await_links(k, t)
            if k % max(1, n_ticks // 10) == 0:
                rate = (k + 1) / max(1e-9, time.monotonic() - wall0)
                self.log.info("tick %d/%d  t=%.1f s  %.0f ticks/s", k, n_ticks, t, rate)
        self._status("finished", n_ticks - 1)
        self.lockstep.await_departure(timeout_s=10.0)
        self.completed = True
        return True

    def _await_links(self, k: int, t: float) -> None:
        """After tick ``k`` (time ``t``): each link change due, said in the status and held for
        until it took effect (``LinkAwait``)."""
        for i, due in enumerate(self.link_awaits):
            if abs(due.t_s - t) <= 0.5 * self._dt:
                self._status("waiting", k, f"link {i}: awaiting {due}")
                held = self.lockstep.await_liveness(due.nodes, due.alive,
                                                    self.scenario.sim.lockstep_timeout_s)
                if self.pacer is not None:
                    self.pacer.slip(held)

    def _commands_in(self, expect: dict[str, int], deadline: float) -> None:
        """Wait until ``deadline`` (wall) for the commands the answers announce; those still
        missing after a second (lost with the network while the router restarted) are asked
        of their senders again (``recent.recover``)."""
        missing = self.bus.wait_for(expect, max(0.0, min(1.0, deadline - time.monotonic())))
        if missing:
            recover(self.bus, missing)
            self.bus.wait_for(expect, max(0.0, deadline - time.monotonic()))

    def _send_again(self, tick: Callable[..., Tick], back: list[str]) -> None:
        """Send the open tick again, for the participants ``back`` that came back while it
        was open (their restart); the others take it as a tick they have run."""
        self.log.warning("sending tick again for %s", ", ".join(back))
        self.bus.publish(self._keys["tick"], tick(rejoin=sorted(self.lockstep.rejoining)),
                         announce=False)
        self.bus.flush_bundle()

    def _publish_hardware(self, k: int, t: float) -> None:
        """What the sim publishes before tick k (t, s): the faults switching, the truth, then
        each unit due, in the order of the task list."""
        self._switch_faults(t)
        now = self._publish_truth(k, t)
        for unit in self.units:
            if unit.due(k):
                unit.step(now)

    def _switch_faults(self, t: float) -> None:
        """Switch the faults due at ``t`` (s), publishing each switch, and move the truth by
        the state disturbances acting on this tick."""
        for s in self.faults.update(t):
            f = s.fault
            self.log.warning("fault %s on sc%d %s at t=%.1f s (magnitude %s)", f.kind,
                             f.spacecraft, "ON" if s.active else "off", t, f.magnitude)
            self.bus.publish(self._keys["faults"], FaultEvent(
                sender=topics.SIM, t_sim=t, spacecraft=f.spacecraft, kind=f.kind,
                active=s.active, magnitude=f.magnitude, start_s=f.start_s, end_s=f.end_s,
                detail=s.detail))
        self.faults.disturb(t)

    def _publish_truth(self, k: int, t: float) -> Sensed:
        """Publish the truth of tick k (t, s) and return it as the units sense it."""
        rel = self.truth.rel_lvlh()
        hw = self.hw
        self._q_now = self._q_lvlh_eci()  # reused for the thrust of this tick
        q_lvlh_body = hw.q_lvlh_body(self._q_now)
        self.bus.publish(self._keys["truth"], TruthState(
            sender=topics.SIM, t_sim=t, spacecraft=self.ids,
            r_lvlh_m=rel[:, :3].tolist(), v_lvlh_mps=rel[:, 3:].tolist(),
            q_lvlh_body=q_lvlh_body.tolist(),
            w_body_radps=hw.attitude.w.tolist(), dv_mps=hw.dv_mps.tolist()))
        return Sensed(k, t, rel, q_lvlh_body, hw.attitude)

    def _status(self, state: str, k: int, reason: str = "") -> None:
        t = k * self.scenario.rates.dt_s
        events = {n: [SimStatus.Event(what=w, t_sim=s) for w, s in e]
                  for n, e in self.lockstep.events_now().items()}
        pace = {} if self.pacer is None else {
            "pace_ceiling": self.pacer.speed, "hard_deadline": self.pacer.hard,
            "late_ticks": dict(self.lockstep.late)}
        self.bus.publish(self._keys["status"], SimStatus(
            sender=topics.SIM, t_sim=t, state=state, k=k, reason=reason,
            rejected_commands=self.rejected_commands,
            participants=events, **pace), announce=False)  # type: ignore[arg-type]
