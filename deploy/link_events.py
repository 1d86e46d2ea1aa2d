"""A rehearsal's link events (docs/hosts.md): a host's link cut, or its delay or loss raised,
from a sim time for a sim duration, applied to the host's link in the rehearsed network (not
in the Bus).

The launcher's clock for them is the sim time of the ground's heartbeats (1 Hz of sim time),
so an event starts at the first heartbeat at or after its time: up to a heartbeat period late,
and by how much is recorded (``<out>/logs/link-events.json``).
"""

from __future__ import annotations

import json
import logging
import threading
from dataclasses import dataclass

from deploy.host_map import HostMap, LinkEvent
from deploy.rehearsal.network import RehearsedNetwork

log = logging.getLogger("insp.links")


@dataclass
class _Applied:
    event: LinkEvent
    started_t_s: float | None = None
    ended_t_s: float | None = None


class LinkEvents:
    """The events of ``host_map`` on ``net``'s links; :meth:`on_time` moves them on."""

    def __init__(self, net: RehearsedNetwork, host_map: HostMap) -> None:
        self.net, self.map = net, host_map
        self._events = [_Applied(e) for e in host_map.events]
        self._lock = threading.Lock()
        self._t_sim = 0.0

    def __enter__(self) -> LinkEvents:
        return self

    def __exit__(self, *exc: object) -> None:
        with self._lock:
            for a in self._events:
                if a.started_t_s is not None and a.ended_t_s is None:
                    self._restore(a, self._t_sim)

    def on_time(self, t_sim: float) -> None:
        """The sim time is ``t_sim`` (s): start and end the events due."""
        with self._lock:
            self._t_sim = t_sim
            for a in self._events:
                e = a.event
                if a.started_t_s is None and t_sim >= e.at_s:
                    a.started_t_s = t_sim
                    normal = self.map.hosts[self._index(e.host)].link
                    self.net.set_link(e.host, e.during(normal), up=not e.cut)
                    log.warning("link of %s %s at sim t=%.1f s (due %.1f s)", e.host,
                                "cut" if e.cut else f"now {e.during(normal)}", t_sim, e.at_s)
                elif (a.started_t_s is not None and a.ended_t_s is None
                      and t_sim >= e.at_s + e.duration_s):
                    self._restore(a, t_sim)

    def _restore(self, a: _Applied, t_sim: float) -> None:
        a.ended_t_s = t_sim
        self.net.set_link(a.event.host, self.map.hosts[self._index(a.event.host)].link)
        log.warning("link of %s restored at sim t=%.1f s", a.event.host, t_sim)

    def _index(self, host: str) -> int:
        return next(i for i, h in enumerate(self.map.hosts) if h.name == host)

    def report(self) -> str:
        """The events as applied (JSON): each with the sim times it started and ended."""
        with self._lock:
            return json.dumps([{**a.event.model_dump(), "started_t_s": a.started_t_s,
                                "ended_t_s": a.ended_t_s} for a in self._events], indent=2)
