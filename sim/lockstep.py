"""The time master's side of the lockstep (docs/architecture.md, Runtime model): which
participants are alive, lost or rejoining, their answers (TickDone) to the current tick, and the
sim's waits on them.

* A participant whose liveliness token goes before the last tick is lost: it is not waited for
  any more, and the sim flies on with its last commands held; unless restarts are supervised
  (``hold_s``): then the open tick waits for it up to ``hold_s``, and is sent again when it is
  back (restored from its critical-data store, it runs the tick as if nothing happened).
* One seen again is named in the ticks' ``rejoin`` until it answers a tick.  One that answers
  the open tick is back even before its token is seen (a restored node runs that tick as it
  catches up, before it announces itself).
* Both are recorded with their sim time (``events``) for the final status.
* An answer counts only for the current tick, and announces only keys of its sender's own space.

Thread-safe: the answers and the liveness changes come on transport threads.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from interfaces.contracts import topics
from interfaces.contracts.messages import TickDone


@dataclass(eq=False)
class Lockstep:
    """The lockstep bookkeeping of the ``participants`` of ``mission``, over ticks 0 to
    ``last_tick``; ``now`` gives the sim time now (s), ``stop`` ends every wait, and with
    ``realtime`` a missing answer is expected (counted, not logged)."""

    participants: list[str]
    mission: str
    last_tick: int
    now: Callable[[], float]
    stop: threading.Event
    log: logging.Logger
    realtime: bool = False
    hold_s: float = 0.0
    """With restarts supervised: how long a lost participant (or the recorder) is waited for,
    wall s (0: the sim flies on at once)."""
    events: dict[str, list[tuple[str, float]]] = field(default_factory=dict)
    """Per participant, ("lost" | "rejoined", sim time s) in order."""
    missed_answers: int = 0
    """Ticks on which a live participant's answer did not come in time."""
    late: dict[str, int] = field(default_factory=dict)
    """Per participant, the ticks its answer did not come in time for."""
    answers: dict[str, dict[str, int]] = field(default_factory=dict)
    """The current tick's answers: participant -> the keys it announced, with their numbers."""
    rejoining: set[str] = field(default_factory=set)
    """Participants seen again after they were lost, until they answer a tick."""
    _answer_k: int = -1
    _alive: set[str] = field(default_factory=set)
    _dead: set[str] = field(default_factory=set)
    _lost_at: dict[str, float] = field(default_factory=dict)
    """wall time (``time.monotonic``) each participant now lost was lost at"""
    _back: set[str] = field(default_factory=set)
    """Participants that came back since the open tick was sent: they are sent it again."""
    _recorder_lost_at: float | None = None
    """wall time the recorder was lost at, while it is gone"""
    held_s: float = 0.0
    """Wall time the open tick waited for lost participants, s."""
    _cond: threading.Condition = field(default_factory=threading.Condition)

    def __post_init__(self) -> None:
        self._prefixes = {p: topics.node_prefix(self.mission, p) + "/" for p in self.participants}

    def on_done(self, msg: TickDone) -> None:
        """A participant's answer to the current tick (its sender is the owner of the key it
        came on: the Bus's admission).  Only keys of its own space count as announced."""
        with self._cond:
            if msg.k == self._answer_k and msg.sender in self._prefixes:
                own = self._prefixes[msg.sender]
                self.answers[msg.sender] = {k: s for k, s in msg.published.items()
                                            if k.startswith(own)}
                self.rejoining.discard(msg.sender)
                if msg.sender in self._dead:  # back before its token: a restarted node
                    self._rejoined(msg.sender)  # answers the open tick as it catches up
                self._cond.notify_all()

    def on_liveness(self, node: str, alive: bool) -> None:
        """Liveliness handler: a participant that disappears is not waited for any more (its
        last commands are held by the hardware, within their own limits), unless restarts are
        supervised (``hold_s``): then the tick waits for it; one that comes back (a stalled
        process resumed, a crashed one restarted) is waited for again, sent the open tick
        again if it came back during it, and named in the ticks' ``rejoin`` until it answers one
        (a node that never saw the sim lost takes them as its present, ``TickClient``).  Both are
        recorded with their sim time for the final status.  The recorder (``topics.RECORDER``) is
        watched too: with ``hold_s``, the clock waits for it (``hold_for_services``)."""
        with self._cond:
            t = self.now()
            if node == topics.RECORDER:
                self._recorder_lost_at = None if alive else time.monotonic()
                if not alive and self.hold_s > 0.0:
                    self.log.error("the recorder is gone at t=%.1f s", t)
            elif alive:
                self._alive.add(node)
                if node in self._dead:
                    self.rejoining.add(node)
                    self._back.add(node)
                    self._rejoined(node)
            elif node in self.participants and node in self._alive:
                self._alive.discard(node)
                if self._answer_k < self.last_tick:
                    self._dead.add(node)
                    self._lost_at[node] = time.monotonic()
                    self.events.setdefault(node, []).append(("lost", t))
                    self.log.error("participant %s lost at t=%.1f s (process died, stalled or "
                                   "disconnected); %s", node, t,
                                   f"holding the clock up to {self.hold_s:.0f} s for its restart"
                                   if self.hold_s > 0.0 else "flying on with its last commands")
            self._cond.notify_all()

    def _rejoined(self, node: str) -> None:
        """Under the lock: lost ``node`` is back in the lockstep, now (its liveliness token
        seen again, or its answer to the open tick, whichever comes first)."""
        t = self.now()
        self._dead.discard(node)
        self._lost_at.pop(node, None)
        self.events.setdefault(node, []).append(("rejoined", t))
        self.log.warning("participant %s rejoined at t=%.1f s", node, t)

    def hold_for_services(self) -> float:
        """Before the next tick, with restarts supervised (``hold_s``): wait while the recorder,
        lost less than ``hold_s`` ago (wall), may still come back (the launcher restarts it), so
        that nothing is sent that no one records.  Returns the wall time held, s (the pacing
        slips by it)."""
        if self.hold_s <= 0.0:  # no restarts supervised: nothing to hold for (every tick)
            return 0.0
        t0 = time.monotonic()
        with self._cond:
            held = False
            while not self.stop.is_set() and self._recorder_lost_at is not None:
                left = self._recorder_lost_at + self.hold_s - time.monotonic()
                if left <= 0.0:
                    break
                if not held:
                    held = True
                    self.log.warning("holding the clock at t=%.1f s while the recorder restarts "
                                     "(up to %.0f s of wall time)", self.now(), self.hold_s)
                self._cond.wait(min(left, 0.5))
        return time.monotonic() - t0 if held else 0.0

    def await_liveness(self, nodes: tuple[str, ...], alive: bool, timeout_s: float) -> float:
        """Wait until every one of ``nodes`` is alive (``alive``) or gone, up to ``timeout_s``
        (wall): a rehearsal's link cut or restored takes effect at this tick, whatever the
        network's timing (:class:`LinkAwait`).  Returns the wall time held, s."""
        t0 = time.monotonic()
        with self._cond:
            while not self.stop.is_set():
                if all((n in self._alive) == alive for n in nodes):
                    return time.monotonic() - t0
                left = t0 + timeout_s - time.monotonic()
                if left <= 0.0:
                    self.log.error("%s not %s within %.0f s; flying on", ", ".join(nodes),
                                   "back" if alive else "lost", timeout_s)
                    break
                self._cond.wait(min(left, 0.5))
        return time.monotonic() - t0

    def wait_for_participants(self, timeout_s: float) -> None:
        """Block until every participant has announced itself (Zenoh liveliness)."""
        deadline = time.monotonic() + timeout_s
        with self._cond:
            while not set(self.participants) <= self._alive:
                left = deadline - time.monotonic()
                if left <= 0 or self.stop.is_set():
                    missing = sorted(set(self.participants) - self._alive)
                    raise TimeoutError(f"participants never joined: {', '.join(missing)}")
                self._cond.wait(min(left, 0.2))

    def open_tick(self, k: int) -> list[str]:
        """Tick ``k`` is about to be sent: forget the previous answers; return the participants
        its ``rejoin`` names, sorted."""
        with self._cond:
            self.answers, self._answer_k = {}, k
            self._back.clear()  # named in this tick's rejoin: no need to send it again
            self.held_s = 0.0
            return sorted(self.rejoining)

    def collect_answers(self, k: int, deadline: float,
                        resend: Callable[[list[str]], None] | None = None,
                        answer_timeout_s: float = 30.0) -> dict[str, int]:
        """Wait for TickDone(k) from every live participant until ``deadline`` (wall,
        ``time.monotonic``), and from one lost less than ``hold_s`` ago until it comes back:
        then ``resend`` (called with the rejoining participants, sorted) sends it the tick
        again, and its answer is waited for ``answer_timeout_s`` more.  Merge what they
        announced.  The wall time spent waiting for lost participants is ``held_s``."""
        t0, held = time.monotonic(), False
        while True:
            with self._cond:
                back = sorted(self._back)
                self._back.clear()
                if not back:
                    waiting, holding = self._unanswered()
                    left = deadline - time.monotonic()
                    if (not waiting or left <= 0) and not holding or self.stop.is_set():
                        break
                    if holding and not held:
                        held = True
                        self.log.warning("tick %d: holding the clock for %s", k,
                                         ", ".join(sorted(holding)))
                    waits = [*holding.values(), *([left] if waiting and left > 0 else [])]
                    self._cond.wait(min([*waits, 0.5]))
                    continue
            if resend is not None:  # outside the lock: the answers come on other threads
                resend(back)
            deadline = max(deadline, time.monotonic() + answer_timeout_s)
        self.held_s = time.monotonic() - t0 if held else 0.0
        return self._merge(k, waiting)

    def _unanswered(self) -> tuple[list[str], dict[str, float]]:
        """Under the lock: the live participants yet to answer, and the lost ones still held
        for, with the wall time left of their hold, s."""
        waiting = [p for p in self.participants if p not in self.answers and p not in self._dead]
        now = time.monotonic()
        holding = {p: self._lost_at[p] + self.hold_s - now for p in self.participants
                   if p not in self.answers and p in self._lost_at}
        return waiting, {p: left for p, left in holding.items() if left > 0.0}

    def _merge(self, k: int, waiting: list[str]) -> dict[str, int]:
        """Count the answers that did not come (``waiting``), merge those that did."""
        with self._cond:
            answers = dict(self.answers)
            waiting = [p for p in waiting if p not in answers]
        if waiting and not self.stop.is_set():
            self.missed_answers += 1
            for p in waiting:
                self.late[p] = self.late.get(p, 0) + 1
            if not self.realtime:
                self.log.warning("tick %d: no answer from %s; holding last commands",
                                 k, ", ".join(waiting))
        merged: dict[str, int] = {}
        for published in answers.values():
            merged.update(published)
        return merged

    def await_departure(self, timeout_s: float) -> None:
        """After the run, wait until the participants have left (their liveliness tokens
        gone), so none of them sees the sim vanish before it has read the status."""
        deadline = time.monotonic() + timeout_s
        with self._cond:
            while self._alive & set(self.participants) and time.monotonic() < deadline:
                self._cond.wait(0.1)

    def events_now(self) -> dict[str, list[tuple[str, float]]]:
        """A copy of ``events``, taken under the lock."""
        with self._cond:
            return {n: list(e) for n, e in self.events.items()}


@dataclass(frozen=True)
class LinkAwait:
    """A rehearsal's link cut (``alive`` False) or restored (True) at sim time ``t_s``
    (``--await-link lost|back:NODES:T``, docs/hosts.md): after the tick at ``t_s`` the sim says
    so in its status (``waiting``, reason ``link <index>: ...``), the launcher changes the link,
    and the sim holds the clock until ``nodes`` are gone or back.  So the cut spacecraft are lost
    from the tick after ``t_s`` and rejoin at the tick after the restore's, whatever the
    network's timing."""

    alive: bool
    nodes: tuple[str, ...]
    t_s: float

    @classmethod
    def parse(cls, text: str) -> LinkAwait:
        """``lost:sc1,sc2:600`` or ``back:sc1,sc2:630``; ValueError saying the form."""
        parts = text.split(":")
        if len(parts) != 3 or parts[0] not in ("lost", "back") or not parts[1]:
            raise ValueError(f"--await-link {text!r}: expected lost|back:NODE[,NODE...]:T_S")
        return cls(parts[0] == "back", tuple(parts[1].split(",")), float(parts[2]))

    def __str__(self) -> str:
        """The form :meth:`parse` reads (the time as Python writes a float: read back the
        same)."""
        return f"{'back' if self.alive else 'lost'}:{','.join(self.nodes)}:{self.t_s!r}"
