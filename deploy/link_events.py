"""A rehearsal's link events (docs/hosts.md): a host's link cut, or its delay or loss raised,
from a sim time for a sim duration, applied to the host's link in the rehearsed network (not
in the Bus).

* **A cut** changes which spacecraft take part in the lockstep, so it must act at a tick, not
  whenever the network notices: the sim is told the cut's times (``--await-link``,
  :meth:`LinkEvents.awaits`), and after the tick at each it says in its status that it waits
  (``sim.lockstep.LinkAwait``).  The launcher then cuts or restores the link
  (:meth:`LinkEvents.on_waiting`) and the sim holds the clock until the host's spacecraft are
  gone (Zenoh's lease, about 10 s of wall time) or back.  The cut spacecraft are lost from the
  tick after ``at_s`` and rejoin at the tick after ``at_s + duration_s``, the same in every run.
* **A delay or loss** changes no result (lockstep), so it is applied by the ground's heartbeats
  (1 Hz of sim time, :meth:`LinkEvents.on_time`): up to a heartbeat period late.

The sim times each event began and ended are in ``<out>/logs/link-events.json``.
"""

from __future__ import annotations

import json
import logging
import threading
from dataclasses import dataclass

from deploy.host_map import HostMap, LinkEvent, LinkSpec
from deploy.rehearsal.netns import RehearsalError
from deploy.rehearsal.network import RehearsedNetwork
from interfaces.contracts import topics
from sim.lockstep import LinkAwait

log = logging.getLogger("insp.links")


@dataclass
class _Applied:
    event: LinkEvent
    started_t_s: float | None = None
    ended_t_s: float | None = None


def cut_nodes(host_map: HostMap, host: str) -> tuple[str, ...]:
    """The lockstep participants a cut of ``host`` takes away: its spacecraft."""
    return tuple(n for n in host_map.hosts[_index(host_map, host)].nodes
                 if topics.spacecraft_of(n) is not None)


def _index(host_map: HostMap, host: str) -> int:
    return next(i for i, h in enumerate(host_map.hosts) if h.name == host)


def check_cuts(host_map: HostMap) -> None:
    """Refuse cuts a rehearsal cannot make: of the hub (the launcher watches the run through
    it), of the sim's host (the clock) or of a host without spacecraft (nothing to hold for)."""
    for e in host_map.events:
        if not e.cut:
            continue
        if e.host == host_map.hub.name:
            raise ValueError(f"host {e.host} is the hub: the launcher watches the run through "
                             "its link, which a rehearsal does not cut")
        if e.host == host_map.host_of(topics.SIM).name or not cut_nodes(host_map, e.host):
            raise ValueError(f"host {e.host}: a rehearsal cuts the link of a host of "
                             "spacecraft (not the sim's)")


class LinkEvents:
    """The events of ``host_map`` on ``net``'s links (module docstring)."""

    def __init__(self, net: RehearsedNetwork, host_map: HostMap) -> None:
        self.net, self.map = net, host_map
        self._events = [_Applied(e) for e in host_map.events]
        self._lock = threading.Lock()
        self._t_sim = 0.0
        self.failures: list[str] = []
        """the link changes the network refused (the run is then not the one asked for)"""

    def __enter__(self) -> LinkEvents:
        return self

    def __exit__(self, *exc: object) -> None:
        with self._lock:
            for a in self._events:
                if a.started_t_s is not None and a.ended_t_s is None:
                    self._end(a, self._t_sim)

    def _awaits(self, a: _Applied) -> tuple[LinkAwait, LinkAwait]:
        """What the sim waits for at a cut's start and end."""
        e, nodes = a.event, cut_nodes(self.map, a.event.host)
        return LinkAwait(False, nodes, e.at_s), LinkAwait(True, nodes, e.at_s + e.duration_s)

    def awaits(self) -> list[str]:
        """The sim's ``--await-link`` values: each cut's start and end, in time order."""
        both = [w for a in self._events if a.event.cut for w in self._awaits(a)]
        return [str(w) for w in sorted(both, key=lambda w: w.t_s)]

    def on_waiting(self, reason: str, t_sim: float) -> None:
        """The sim waits at ``t_sim`` for a link change (its status' ``reason``, ``link <i>:
        awaiting <LinkAwait>``): make it."""
        what = reason.rpartition("awaiting ")[2]
        with self._lock:
            self._t_sim = max(self._t_sim, t_sim)
            for a in self._events:
                if not a.event.cut:
                    continue
                start, end = (str(w) for w in self._awaits(a))
                if a.started_t_s is None and what == start:
                    self._start(a, t_sim)
                elif a.ended_t_s is None and what == end:
                    self._end(a, t_sim)

    def on_time(self, t_sim: float) -> None:
        """The sim time is ``t_sim`` (s): start and end the delay and loss events due."""
        with self._lock:
            self._t_sim = max(self._t_sim, t_sim)
            for a in self._events:
                e = a.event
                if e.cut:
                    continue
                if a.started_t_s is None and t_sim >= e.at_s:
                    self._start(a, t_sim)
                elif (a.started_t_s is not None and a.ended_t_s is None
                      and t_sim >= e.at_s + e.duration_s):
                    self._end(a, t_sim)

    def _start(self, a: _Applied, t_sim: float) -> None:
        e, normal = a.event, self.map.hosts[_index(self.map, a.event.host)].link
        a.started_t_s = t_sim
        if self._set(e.host, e.during(normal), not e.cut, t_sim):
            log.warning("link of %s %s at sim t=%.1f s (due %.1f s)", e.host,
                        "cut" if e.cut else f"now {e.during(normal)}", t_sim, e.at_s)

    def _end(self, a: _Applied, t_sim: float) -> None:
        a.ended_t_s = t_sim
        host = a.event.host
        if self._set(host, self.map.hosts[_index(self.map, host)].link, True, t_sim):
            log.warning("link of %s restored at sim t=%.1f s", host, t_sim)

    def _set(self, host: str, link: LinkSpec, up: bool, t_sim: float) -> bool:
        """Change ``host``'s link; a refusal is logged and kept in ``failures`` (called on
        the launcher's bus threads and at its exit: nothing is raised)."""
        try:
            self.net.set_link(host, link, up)
        except RehearsalError as e:
            self.failures.append(f"link of {host} not changed at sim t={t_sim:.1f} s: {e}")
            log.error("%s", self.failures[-1])
            return False
        return True

    def report(self) -> str:
        """The events as applied (JSON): each with the sim times it started and ended."""
        with self._lock:
            return json.dumps([{**a.event.model_dump(), "started_t_s": a.started_t_s,
                                "ended_t_s": a.ended_t_s} for a in self._events], indent=2)
