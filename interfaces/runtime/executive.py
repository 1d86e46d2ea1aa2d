"""The rate-group executive: hosts a node's apps and runs them on the sim's ticks.

Per tick k (t = k·dt): wait until the messages announced in the Tick have arrived (barrier), then
for each due rate group (high every tick, mid every ω_high/ω_mid ticks, low every ω_high/ω_low),
deliver the due messages and run the group's apps in declaration order; a group whose run takes
more CPU time than its period × ``sim.cycle_budget_scale`` counts a cycle slip (an overrun is
reported, never absorbed), logged with the app that took longest, the time and the duration.
The budget is judged on the thread's CPU time, the flight software's own work: the wall time of
a run on a shared host also holds the time other processes had the core.  A group's first run
in a process is its start-up (code loaded on first use): logged when over budget, not counted
(:func:`judge_run`).  At ω_mid the node publishes its heartbeat, executive stats and link
stats.  Finally it answers the sim with TickDone(k), announcing what it published.

The same executive runs onboard (one per spacecraft) and on the ground.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import ClassVar, Literal

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.catalogue import Topic
from interfaces.contracts.messages import (
    ExecStats,
    GroupStats,
    Heartbeat,
    LinkStats,
    RateGroupName,
    SimStatus,
    Tick,
    TickDone,
)
from interfaces.contracts.scenario import Scenario
from interfaces.runtime.admission import MAX_AHEAD_S
from interfaces.runtime.app import RATE_GROUPS, App
from interfaces.runtime.bus import Bus
from interfaces.runtime.recent import recover


@dataclass
class GroupCount:
    """A rate group's running statistics (published as :class:`GroupStats` at ω_mid):
    ``max_exec_ms`` is the longest run counted, in ms of CPU time."""

    budget_ms: float
    runs: int = 0
    cycle_slips: int = 0
    max_exec_ms: float = 0.0

    def message(self) -> GroupStats:
        return GroupStats(runs=self.runs, cycle_slips=self.cycle_slips,
                          max_exec_ms=self.max_exec_ms, budget_ms=self.budget_ms)


RunVerdict = Literal["within", "start-up", "slip"]
"""A group run judged: within its budget, a start-up overrun (not counted), a cycle slip."""


def judge_run(count: GroupCount, cpu_ms: float, first: bool) -> RunVerdict:
    """Count a run of the group ``count`` that took ``cpu_ms`` (ms of CPU time); ``first``:
    the group's first run in this process.  A first run loads the code its apps reach (the
    modules they import on first use, the compiled kernels not loaded before the clock
    started): it is the process's start-up, not a cycle of the flight software, so neither
    its time nor an overrun is counted.  Any later run over ``budget_ms`` is a cycle slip."""
    if first:
        return "start-up" if cpu_ms > count.budget_ms else "within"
    count.runs += 1
    count.max_exec_ms = max(count.max_exec_ms, cpu_ms)
    if cpu_ms <= count.budget_ms:
        return "within"
    count.cycle_slips += 1
    return "slip"


@dataclass(eq=False)
class Executive:
    """A node's rate-group executive (its own topics are declared for the wiring check; its
    lockstep inputs are ``TickClient.SUBSCRIBES``)."""

    PUBLISHES: ClassVar[tuple[Topic, ...]] = (
        cat.TICK_DONE, cat.HEARTBEAT, cat.EXEC_STATS, cat.LINK_STATS)

    bus: Bus
    scenario: Scenario
    apps: list[App]
    log: logging.Logger = field(default_factory=lambda: logging.getLogger("insp.exec"))
    barrier_timeout_s: float = 5.0
    """How long a tick waits for the messages it announces (s, wall).  They were all sent before
    the sim sent the tick, so they arrive in milliseconds; only a message lost in a reconnection
    (a node rejoining) is waited for this long."""
    at_tick_end: Callable[[], None] | None = None
    """Called at the end of a tick, its answer sent (the critical-data store is written there:
    ``interfaces.runtime.restart``)."""
    last_done: TickDone | None = None
    """The answer to the last tick run."""
    recover_after_s: float = 1.0
    """After this long (s, wall) the messages a tick still misses are asked of their
    publishers again (``Bus.recover``)."""

    def __post_init__(self) -> None:
        rates = self.scenario.rates
        scale = self.scenario.sim.cycle_budget_scale
        self.period = {g: rates.ticks_per(g) for g in RATE_GROUPS}
        self.groups = {g: [a for a in self.apps if a.RATE == g] for g in RATE_GROUPS}
        self.stats = {
            g: GroupCount(budget_ms=1e3 * self.period[g] * rates.dt_s * scale) for g in RATE_GROUPS
        }
        self.app_errors = 0
        self.barrier_timeouts = 0
        self.ticks = 0
        self._started: set[RateGroupName] = set()
        """The groups that ran in this process (a restarted process starts again)."""
        self._run: list[tuple[str, float]] = []
        """(app, ms of CPU time) of the group run under way."""
        self._run_t = 0.0
        m, n = self.bus.mission, self.bus.node
        self._keys = {
            "done": cat.TICK_DONE.key(m, n), "heartbeat": cat.HEARTBEAT.key(m, n),
            "stats": cat.EXEC_STATS.key(m, n), "links": cat.LINK_STATS.key(m, n),
        }
        for app in self.apps:
            app.wire()

    def run_tick(self, tick: Tick, barrier: bool = True) -> None:
        """Run every due rate group for ``tick`` and answer with TickDone.  ``barrier``: wait
        first for the messages the tick announces (not needed when the tick runs inside the
        sim's publish on the in-process transport: every message was delivered as it was
        published)."""
        if not self.begin_tick(tick, barrier):
            return
        step_together([self], tick)  # an executive alone is a fleet of one
        self.end_tick(tick)
        self.bus.flush_bundle()
        self.tick_ended()

    def begin_tick(self, tick: Tick, barrier: bool) -> bool:
        """The start of ``tick``: False when this node ran it already (its answer is then sent
        again); otherwise, with ``barrier``, wait for the messages the tick announces."""
        if self.last_done is not None and tick.k == self.last_done.k:
            self._answer_again()
            return False
        missing = self._barrier(tick) if barrier else []
        if missing:
            self.barrier_timeouts += 1
            self.log.warning("%s tick %d: announced messages missing after %.1f s: %s",
                             self.bus.node, tick.k, self.barrier_timeout_s,
                             ", ".join(sorted(missing)))
        return True

    def due_groups(self, k: int) -> list[RateGroupName]:
        """The rate groups due at tick ``k``, in the order they run (high, mid, low)."""
        return [g for g in RATE_GROUPS if k % self.period[g] == 0]

    def run_app(self, app: App, t: float) -> None:
        """One app's step at ``t`` (s), its CPU time kept for the group's run
        (:meth:`count_group`); a failure is counted and logged, never raised."""
        started = time.thread_time()
        try:
            app.step(t)
        except Exception:  # noqa: BLE001 - one app's failure must not stop the node
            self.app_failed(app, t)
        self.note_app(app, 1e3 * (time.thread_time() - started), t)

    def note_app(self, app: App, cpu_ms: float, t: float) -> None:
        """``app`` ran at ``t`` (s) in a step shared with other members of its fleet
        (``App.step_all``), its share of the CPU time ``cpu_ms`` (ms), for the group's run."""
        self._run.append((app.NAME, cpu_ms))
        self._run_t = t

    def app_failed(self, app: App, t: float, batched: bool = False) -> None:
        """Count and log (rate-limited) a failure of ``app`` at ``t`` (s), raised in its own
        step or, ``batched``, in a step it shared with its fleet (every member counts it)."""
        self.app_errors += 1
        if self.app_errors <= 5 or self.app_errors % 100 == 0:
            self.log.exception("%s: app %s failed at t=%.3f s%s (error #%d)", self.bus.node,
                               app.NAME, t, " in its fleet's shared step" if batched else "",
                               self.app_errors)

    def count_group(self, g: RateGroupName, wall_ms: float) -> None:
        """Group ``g`` ran its apps (:meth:`run_app`; ``wall_ms``: the run's wall time, ms):
        the run is judged on its CPU time (:func:`judge_run`), and an overrun logged."""
        run, self._run = self._run, []
        cpu_ms = sum(ms for _, ms in run)
        first = g not in self._started
        self._started.add(g)
        verdict = judge_run(self.stats[g], cpu_ms, first)
        if verdict != "within":
            self._log_overrun(g, verdict, cpu_ms, wall_ms, run)

    def _log_overrun(self, g: RateGroupName, verdict: RunVerdict, cpu_ms: float,
                     wall_ms: float, run: list[tuple[str, float]]) -> None:
        """Log a group run over budget: which group, when, how long, which app took longest
        (every start-up; the first 5 slips, then every 100th)."""
        slips = self.stats[g].cycle_slips
        if verdict == "slip" and not (slips <= 5 or slips % 100 == 0):
            return
        app, app_ms = max(run, key=lambda r: r[1], default=("none", 0.0))
        what = ("start-up, its first run: not counted" if verdict == "start-up"
                else f"cycle slip #{slips}")
        self.log.warning("%s: %s group took %.1f ms of CPU (%.1f ms wall) at t=%.3f s, over its "
                         "%.0f ms budget; %s took %.1f ms (%s)", self.bus.node, g, cpu_ms,
                         wall_ms, self._run_t, self.stats[g].budget_ms, app, app_ms, what)

    def end_tick(self, tick: Tick) -> None:
        """The end of ``tick``: housekeeping at ω_mid and the answer (TickDone); once the
        process's bundle is sent, :meth:`tick_ended`."""
        self.ticks += 1
        if tick.k % self.period["mid"] == 0:
            self._publish_housekeeping(tick.t_sim, tick.k)
        self.last_done = TickDone(sender=self.bus.node, t_sim=tick.t_sim, k=tick.k,
                                  published=self.bus.published_since_last())
        self.bus.publish(self._keys["done"], self.last_done, announce=False)

    def tick_ended(self) -> None:
        """After the answer went: the critical-data store (``at_tick_end``), off the sim's
        wait."""
        if self.at_tick_end is not None:
            self.at_tick_end()

    def _answer_again(self) -> None:
        """The sim sent the tick this node last ran again (it lost the node while the tick
        was open, and sees it back): send the answer again, as it was (the first may have been
        lost with the network; if not, the sim drops this one as a duplicate)."""
        assert self.last_done is not None
        self.log.warning("%s: the sim sent tick %d again; answering it again", self.bus.node,
                         self.last_done.k)
        self.bus.send_again(self._keys["done"], self.last_done)

    CRITICAL: ClassVar[tuple[str, ...]] = (
        "stats", "app_errors", "barrier_timeouts", "ticks", "last_done")
    """The executive's own critical data: its counters and its last answer."""

    def checkpoint(self) -> dict[str, object]:
        """The ``CRITICAL`` attributes (for the node's critical-data store)."""
        return {name: getattr(self, name) for name in self.CRITICAL}

    def restore(self, saved: dict[str, object]) -> None:
        """Take back a ``checkpoint``."""
        for name in self.CRITICAL:
            setattr(self, name, saved[name])

    def _barrier(self, tick: Tick) -> list[str]:
        """Wait for the messages ``tick`` announces; those still missing after
        ``recover_after_s`` are asked of their publishers again (``Bus.recover``: they were
        sent while this process restarted, or lost with the network), then waited for up to
        ``barrier_timeout_s``.  Returns the keys still missing."""
        missing = self.bus.wait_for(tick.expect, self.recover_after_s)
        if missing:
            recover(self.bus, missing)
            missing = self.bus.wait_for(tick.expect, self.barrier_timeout_s)
        return missing

    def _publish_housekeeping(self, t: float, k: int) -> None:
        node = self.bus.node
        self.bus.publish(self._keys["heartbeat"], Heartbeat(
            sender=node, t_sim=t, node=node, apps=[a.NAME for a in self.apps], k=k))
        self.bus.publish(self._keys["stats"], ExecStats(
            sender=node, t_sim=t, node=node,
            groups={g: s.message() for g, s in self.stats.items()},
            app_errors=self.app_errors + self.bus.stats.handler_errors,
            invalid_dropped=self.bus.stats.invalid_dropped, refused=self.bus.stats.refused,
            barrier_timeouts=self.barrier_timeouts, ticks=self.ticks))
        if self.bus.channel is not None:
            self.bus.publish(self._keys["links"], LinkStats(
                sender=node, t_sim=t, node=node, links=self.bus.channel.counters()))


def step_together(members: Sequence[Executive], tick: Tick) -> None:
    """The rate-group loop, for an executive alone (a fleet of one) and for the executives of
    the spacecraft one process hosts (``interfaces.runtime.fleet``).  For each group due at
    ``tick``: every member's bus delivers its due messages; then each app slot (the same app
    class in the same place on every member) runs for all members together, its class's
    :meth:`App.step_all` first and every member it leaves by its own ``step``; each member's
    group run is judged on its CPU time (``Executive.count_group``).  A message a member
    publishes is delivered at a later tick (``Inbox``), so the order changes nothing any
    member receives."""
    t = tick.t_sim
    for g in members[0].due_groups(tick.k):
        for m in members:
            m.bus.dispatch(t)
        spent = [0.0] * len(members)
        for slot in zip(*(m.groups[g] for m in members), strict=True):
            _step_slot(members, slot, t, spent)
        for m, s in zip(members, spent, strict=True):
            m.count_group(g, 1e3 * s)


def _step_slot(members: Sequence[Executive], apps: Sequence[App], t: float,
               spent: list[float]) -> None:
    """One app slot of ``members`` at ``t`` (s): the members' apps stepped together where
    their class batches (:func:`_step_shared`), the others each alone.  ``spent``: each
    member's wall time so far (s)."""
    alone = (range(len(apps)) if type(apps[0]).step_all is App.step_all
             else _step_shared(members, apps, t, spent))
    for i in alone:
        start = time.perf_counter()
        members[i].run_app(apps[i], t)
        spent[i] += time.perf_counter() - start


def _step_shared(members: Sequence[Executive], apps: Sequence[App], t: float,
                 spent: list[float]) -> list[int]:
    """Step ``apps`` together (``App.step_all``); the indices of those it left to their own
    step.  Its CPU and wall time are shared evenly among the members it stepped; a failure of
    the shared step is every member's."""
    wall, cpu = time.perf_counter(), time.thread_time()
    try:
        left = {id(a) for a in type(apps[0]).step_all(apps, t)}
    except Exception:  # noqa: BLE001 - the fleet's failure must not stop the process
        left = set()
        for m, app in zip(members, apps, strict=True):
            m.app_failed(app, t, batched=True)
    done = [i for i, app in enumerate(apps) if id(app) not in left]
    cpu_ms = 1e3 * (time.thread_time() - cpu) / max(1, len(done))
    wall_s = (time.perf_counter() - wall) / max(1, len(done))
    for i in done:
        members[i].note_app(apps[i], cpu_ms, t)
        spent[i] += wall_s
    return [i for i, app in enumerate(apps) if id(app) in left]


def serve_together(clients: Sequence[TickClient], stop: threading.Event | None = None) -> None:
    """Run the ticks of ``clients``, the nodes one process hosts (sharing one ``tick_queue``),
    on the calling thread until every one is done (``TickClient.done``) or ``stop`` is set.
    Every tick queued before the end is run."""
    ticks = clients[0].tick_queue
    if any(c.tick_queue is not ticks for c in clients):
        raise ValueError("clients served together must share one tick queue")
    while not (stop is not None and stop.is_set()):
        try:
            item = ticks.get(timeout=0.5)
        except queue.Empty:
            item = None
        if item is not None:
            client, epoch, tick = item
            client._run(epoch, tick)
        elif all(c.done for c in clients):
            return


MAX_TICK_GAP = 100
"""Most ticks a node may find skipped between two it receives (none are, on a reliable link);
fewer when they span more than ``admission.MAX_AHEAD_S`` of simulated time."""


@dataclass(eq=False)
class TickClient:
    """Lockstep participation of a node: receives the sim's ticks, runs them on the executive.

    ``synchronous`` (in-process transport): a tick runs inside the sim's publish call.
    Otherwise ticks queue up and ``serve()`` runs them on the calling (main) thread until the sim
    reports the run finished, or the sim's liveliness token has been gone for
    ``rejoin_grace_s`` (wall).  A node cut off from the sim (its process stalled, its link or
    the router lost) that sees the sim again within that time goes on from its own tick: the
    sim may have held the clock for it (restarts supervised), and its next tick is then the
    open one, sent again (answered again if the node ran it, ``Executive.run_tick``), or the
    one after.  If instead the sim flew on, its present is too far ahead: the node rejoins, it
    forgets its tick count, clock and sequence numbers and runs that tick.  So does a node that
    the sim names in a tick's ``rejoin`` while that tick is too far ahead of its own (the sim
    lost it and sees it again, though the node never saw the sim lost, or it took a tick of the
    lost epoch after rejoining).  Ticks are queued with their epoch; those of a lost epoch are
    dropped, not run.  A node whose token comes back may number its messages from 1 again
    (``Admission.restarted``)."""

    SUBSCRIBES: ClassVar[tuple[Topic, ...]] = (cat.TICK, cat.SIM_STATUS)

    executive: Executive
    synchronous: bool = False
    fleet: Callable[[Executive, Tick, bool], None] | None = None
    """How a tick this node took is run when it steps with other nodes of its process
    (``interfaces.runtime.fleet.Fleet.take``: once every member has taken it); None: at once,
    alone."""
    tick_queue: queue.Queue[tuple[TickClient, int, Tick] | None] = field(
        default_factory=queue.Queue)
    """(client, epoch, tick) to run, shared by the clients one serving thread runs
    (:func:`serve_together`); None wakes that thread."""
    finished: threading.Event = field(default_factory=threading.Event)
    sim_lost: bool = False
    rejoin_grace_s: float = 60.0
    _last_k: int = -1
    _epoch: int = 0
    """How many times this node lost the lockstep and rejoined it."""
    _served_epoch: int = 0
    _lost_at: float = 0.0
    _sim_back: bool = False
    """The sim was lost and is back, and no tick was taken since."""

    def __post_init__(self) -> None:
        bus = self.executive.bus
        rates = self.executive.scenario.rates
        self._n_ticks = self.executive.scenario.n_ticks
        self._max_gap = max(1, min(MAX_TICK_GAP, int(MAX_AHEAD_S / rates.dt_s + 1e-9)))
        bus.admission.judged_by_subscriber.add(cat.TICK.key(bus.mission))
        bus.subscribe(cat.TICK.key(bus.mission), Tick, self._on_tick, immediate=True)
        bus.subscribe(cat.SIM_STATUS.key(bus.mission), SimStatus, self._on_status, immediate=True)

    @property
    def last_k(self) -> int:
        """The last tick this node took (-1: none yet in this epoch)."""
        return self._last_k

    def resume_after(self, k: int) -> None:
        """Go on after tick ``k`` (restored from the critical-data store)."""
        self._last_k = k

    def catch_up(self, tick: Tick) -> None:
        """Run ``tick``, one the sim sent while this process was down, now, on this thread
        (``interfaces.runtime.restart``)."""
        self._last_k = tick.k
        self.executive.bus.admission.advance(tick.t_sim)
        self.executive.run_tick(tick)

    def _on_tick(self, tick: Tick) -> None:
        if tick.k == self._last_k >= 0:  # the open tick sent again, for a node back
            if self.executive.bus.node in tick.rejoin:
                self._take(tick)  # ours: answer it again (``Executive.run_tick``)
            return
        why = self._implausible(tick)
        if why and (self.executive.bus.node in tick.rejoin or self._sim_back):
            self._lose_epoch(f"the sim's tick {tick.k} is past its tick {self._last_k} ("
                             + ("the sim flew on while it was cut off)" if self._sim_back
                                else "the sim names it rejoining)"))
            why = self._implausible(tick)
        if why:
            bus = self.executive.bus
            bus.refuse(cat.TICK.key(bus.mission), "tick", f"tick k={tick.k}: {why}")
            return
        self._last_k, self._sim_back = tick.k, False
        self.executive.bus.admission.advance(tick.t_sim)
        self._take(tick)

    def _take(self, tick: Tick) -> None:
        """Run ``tick`` now (synchronous) or queue it for ``serve``."""
        if self.synchronous:
            self._step(tick, barrier=not self.executive.bus.transport.synchronous)
        else:
            self.tick_queue.put((self, self._epoch, tick))

    def _step(self, tick: Tick, barrier: bool) -> None:
        """Run ``tick``: alone, or with the nodes this one steps with (``fleet``)."""
        if self.fleet is not None:
            self.fleet(self.executive, tick, barrier)
        else:
            self.executive.run_tick(tick, barrier=barrier)

    def _implausible(self, tick: Tick) -> str:
        """Why ``tick`` cannot be the sim's next tick ("" if it can): tick numbers only increase,
        by at most ``MAX_TICK_GAP`` and ``admission.MAX_AHEAD_S`` of time, stay within the run,
        and match the sim's clock t = k·dt."""
        rates, n_ticks = self.executive.scenario.rates, self._n_ticks
        if not 0 <= tick.k < n_ticks:
            return f"outside the run's {n_ticks} ticks"
        if tick.dt_s != rates.dt_s or abs(tick.t_sim - tick.k * rates.dt_s) > 1e-6:
            return f"time t={tick.t_sim:.6g} s, dt={tick.dt_s:g} s off the clock k·{rates.dt_s:g} s"
        if tick.k <= self._last_k:
            return f"not after tick {self._last_k}"
        if self._last_k >= 0 and tick.k > self._last_k + self._max_gap:
            return f"{tick.k - self._last_k} ticks after tick {self._last_k}"
        return ""

    def _on_status(self, status: SimStatus) -> None:
        if status.state in ("finished", "aborted"):
            self.finished.set()
            self.tick_queue.put(None)

    def on_liveness(self, node: str, alive: bool) -> None:
        """Liveliness handler: the sim lost (see the class docstring), the sim back (rejoin),
        another node back (its sequence numbers may start again: ``Admission.restarted``)."""
        bus = self.executive.bus
        if node == topics.SIM and not alive:
            self.sim_lost, self._lost_at = True, time.monotonic()
            self.tick_queue.put(None)
        elif node == topics.SIM and self.sim_lost:
            self.sim_lost, self._sim_back = False, True
            self.executive.log.warning("%s: the sim is back", self.executive.bus.node)
        elif alive and node not in (bus.node, topics.RECORDER):
            bus.admission.restarted(topics.node_prefix(bus.mission, node) + "/")

    def _lose_epoch(self, why: str) -> None:
        """Rejoin the lockstep at the next tick: the ticks queued so far belong to a lost epoch
        (dropped by ``serve``, which forgets the bus's clock and sequence numbers before it
        runs the first tick of the new one)."""
        self.sim_lost, self._last_k = False, -1
        self._epoch += 1
        if self.synchronous:  # the next tick runs on this thread: forget here
            self.executive.bus.admission.forget()
            self._served_epoch = self._epoch
        else:
            self.tick_queue.put(None)  # wakes the serving thread
        self.executive.log.warning("%s: %s; rejoining the lockstep", self.executive.bus.node,
                                   why)

    def serve(self, stop: threading.Event | None = None) -> None:
        """Run ticks until finished, the sim is lost for good, or ``stop`` is set."""
        serve_together([self], stop)

    @property
    def done(self) -> bool:
        """Whether this node runs no more ticks: the run finished, or the sim was lost for
        longer than ``rejoin_grace_s``."""
        return self.finished.is_set() or self._gone()

    def _run(self, epoch: int, tick: Tick) -> None:
        """Run a queued tick unless its epoch was lost.  The first tick of a new epoch first
        forgets the bus's clock and sequence numbers, on this thread: forgotten on the
        receiving thread, a tick of the lost epoch still running here set the clock back to its
        own time, and every message of the sim's present was then refused as dated too far
        ahead (the node never rejoined)."""
        if epoch < self._epoch:
            return
        if epoch > self._served_epoch:
            self.executive.bus.admission.forget()
            self.executive.bus.admission.advance(tick.t_sim)
            self._served_epoch = epoch
        self._step(tick, barrier=True)

    def _gone(self) -> bool:
        """Whether the sim has been lost for longer than ``rejoin_grace_s``."""
        return self.sim_lost and time.monotonic() - self._lost_at > self.rejoin_grace_s
