"""Recorder process: ``python -m ground.archive.record --scenario F --out run.mcap``.

Subscribes to every key of the mission and archives each message, with its JSON schema, in an
MCAP file (Foxglove opens it).  SIGINT/SIGTERM finish the file cleanly (summary and footer).

When ``--out`` exists already (the recorder was restarted, by the launcher's
``--restart-on-crash``, with the same command), it continues the run's archive in the next
free segment, ``run-1.mcap``, ``run-2.mcap``, ... (``ground/archive/segments.py``): never over
what exists, with the same run metadata and a ``segment`` record.  Restarted, it first records
what every node keeps (``interfaces.runtime.recent``): its last ticks, and all it sent since the
last tick the recorder told it was archived.  After each chunk it closes (one every ω_mid
period's worth of ticks, and every 2 s of wall time) the recorder tells every node the sim
time of the last tick written (``interfaces.runtime.recent.archived_key``), so that the chunk
in progress when it was killed, what was in flight to it and what was sent before the sim
held the clock are all among what the nodes keep, however late the sim held it.  It declares
its liveliness token (``topics.recorder_token``) once subscribed and caught up, ready to
record (the sim holds the clock until then).  When the network goes down (the sim's token
gone: the router died) it takes the token back, and once the sim is seen again records what
the nodes keep before it declares it again, asking each node until it answers (the nodes
reconnect one by one).
"""

from __future__ import annotations

import argparse
import logging
import threading
import time
from typing import Any

from ground.archive.mcap_file import Pending
from ground.archive.metadata import run_metadata
from ground.archive.recorder import McapRecorder, prepare_raw
from ground.archive.segments import claim_segment, with_segment
from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.topology import topology
from interfaces.runtime.cli import add_node_args, open_zenoh, start_node
from interfaces.runtime.recent import archived_key, fetch
from interfaces.runtime.zenoh_transport import ZenohTransport


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ground.archive.record", description=__doc__)
    add_node_args(parser)
    parser.add_argument("--out", required=True,
                        help="MCAP file to write (if it exists: the run's next segment)")
    parser.add_argument("--transport-name", default="zenoh", help="recorded in the metadata")
    args = parser.parse_args(argv)
    start = start_node(args, "recorder")
    log, mission = start.log, start.mission
    with open(args.scenario, encoding="utf-8") as f:
        meta = run_metadata(start.scenario, args.transport_name, f.read())
    path, segment = claim_segment(args.out)
    rec = McapRecorder(path, with_segment(meta, args.out, segment))
    transport = open_zenoh(args)
    nodes = [topics.SIM, *topology(start.scenario).participants]
    gate = _Gate(rec, cat.TICK.key(mission), start.scenario.rates.ticks_per("mid"))
    try:
        if segment:  # restarted: what the nodes keep, in order
            gate.hold()
        transport.subscribe(topics.mission_wildcard(mission), gate.record)
        if segment:
            gate.release(_recent(transport, mission, nodes, log, start.stop))
        presence = _Presence(transport, topics.recorder_token(mission), gate)
        transport.watch_alive(topics.alive_token(mission, topics.SIM), presence.on_sim)
        log.info("recording %s to %s", topics.mission_wildcard(mission), path)
        flushed, told = time.monotonic(), -1
        while not start.stop.wait(0.1):
            if presence.sim_back.is_set():  # the network is back (the router restarted)
                presence.sim_back.clear()
                holds = gate.holds
                gate.release(_recent(transport, mission, nodes, log, start.stop), ending=holds)
                presence.announce()
            if time.monotonic() - flushed > 2.0:
                gate.flush()  # and at least every 2 s of wall time
                flushed = time.monotonic()
            told = _tell_archived(transport, mission, nodes, gate.archived_ns, told)
    finally:
        transport.close()  # no callback can write after this
        gate.release([])
        rec.close()
    log.info("archive closed: %d messages recorded, %d invalid", rec.recorded, rec.invalid)
    return 0


class _Gate:
    """What the recorder writes, in order.  Live samples go to the file as they come, and a
    chunk is closed at every ``every``-th tick (each ω_mid period of sim time: what a killed
    recorder loses the nodes keep until told it is archived, ``archived_ns``,
    ``interfaces.runtime.recent``).  While the network is down, or while a restarted
    recorder takes what the nodes kept, live samples wait (``hold``); ``release`` then writes
    those kept that were not written yet and the waiting ones, sorted by sim time, so that
    every key's messages stay in order in the archive."""

    def __init__(self, rec: McapRecorder, tick_key: str, every: int) -> None:
        self._rec, self._tick_key, self._every = rec, tick_key, every
        self._lock = threading.Lock()
        self._held = False
        self._waiting: list[Pending] = []
        self._last: dict[str, tuple[int, int]] = {}
        """Per key, the (sim time ns, number) of the last sample written."""
        self._ticks = 0
        self._holds = 0
        self.archived_ns = -1
        """The sim time of the last tick written before the last chunk closed, ns (-1: none):
        the archive holds for good every message received before it."""

    def record(self, key: str, type_name: str, payload: bytes) -> None:
        """Transport callback: one live sample."""
        pending = prepare_raw(key, type_name, payload)
        with self._lock:
            if self._held:
                self._waiting.append(pending)
            else:
                self._write(pending)

    @property
    def holds(self) -> int:
        """How many times live samples were made to wait (``release`` names the one it ends)."""
        return self._holds

    def hold(self) -> None:
        """Let live samples wait (the network is down, or the nodes' recent ticks come)."""
        with self._lock:
            self._held = True
            self._holds += 1

    def release(self, recent: list[Pending], ending: int | None = None) -> int:
        """Write ``recent`` and the waiting samples, sorted by sim time, leaving out those
        written already (a key's sample not after its last written); write live ones again,
        unless a hold came after ``ending`` (the ``holds`` count when the recent ones were
        asked for: the network went down again meanwhile).  Returns the samples written."""
        with self._lock:
            merged = sorted([*recent, *self._waiting], key=_order)
            self._waiting = []
            self._held = ending is not None and ending != self._holds
            written = 0
            for pending in merged:
                if _place(pending) > self._last.get(_key(pending), (-1, -1)):
                    self._write(pending)
                    written += 1
            return written

    def flush(self) -> None:
        """Close the chunk in progress (``archived_ns`` follows)."""
        with self._lock:
            self._flush()

    def _flush(self) -> None:
        self._rec.flush()
        self.archived_ns = self._last.get(self._tick_key, (-1, -1))[0]

    def _write(self, pending: Pending) -> None:
        self._rec.take(pending)
        self._last[_key(pending)] = _place(pending)
        if _key(pending) == self._tick_key:
            self._ticks += 1
            if self._ticks % self._every == 0:
                self._flush()


def _key(pending: Pending) -> str:
    return pending[0]


def _place(pending: Pending) -> tuple[int, int]:
    """A sample's place among its key's: (sim time ns, number)."""
    return pending[5] or 0, pending[6]


def _order(pending: Pending) -> tuple[int, str, int]:
    """A sample's place in the archive: sim time, key, number."""
    return pending[5] or 0, pending[0], pending[6]


class _Presence:
    """The recorder's liveliness token, taken back while the network is down: the sim holds
    the clock until it is declared again, once the recorder has recorded what the nodes sent
    while the router was away (still kept of their last ticks)."""

    def __init__(self, transport: ZenohTransport, token_key: str, gate: _Gate) -> None:
        self._session, self._key, self._gate = transport.session, token_key, gate
        self._token: Any = None
        self._sim_lost = False
        self._lock = threading.Lock()
        self.sim_back = threading.Event()
        self.announce()

    def announce(self) -> None:
        """Declare the token (ready to record), unless the network is down again."""
        with self._lock:
            if self._token is None and not self._sim_lost:
                self._token = self._session.liveliness().declare_token(self._key)

    def on_sim(self, _node: str, alive: bool) -> None:
        """Liveliness of the sim's token, as this session sees it: gone means the network is
        down (or the sim ended): live samples wait; back after that, the router is back."""
        with self._lock:
            if not alive:
                self._sim_lost = True
                self._gate.hold()
                if self._token is not None:
                    self._token.undeclare()
                    self._token = None
            elif self._sim_lost:
                self._sim_lost = False
                self.sim_back.set()


def _tell_archived(transport: ZenohTransport, mission: str, nodes: list[str], archived_ns: int,
                   told_ns: int) -> int:
    """Tell every one of ``nodes`` that the archive holds every tick up to ``archived_ns`` (sim
    time, ns), if that is news (``told_ns`` was said last); returns what is said now."""
    if archived_ns > told_ns:
        for node in nodes:
            transport.notify(archived_key(mission, node, archived_ns))
    return max(archived_ns, told_ns)


FETCH_TIMEOUT_S = 10.0
"""How long a node's reply to what it kept is waited for (s, wall; the sim holds the clock
meanwhile): a node of a loaded host may be slow to answer."""
ASK_AGAIN_FOR_S = 30.0
"""How long a node that does not answer (not back on the network yet: the router restarted,
or the node itself) is asked again, every half second (s, wall; the sim holds the clock for
the recorder, and for every participant lost)."""


def _recent(transport: ZenohTransport, mission: str, nodes: list[str], log: logging.Logger,
            stop: threading.Event) -> list[Pending]:
    """What ``nodes`` sent in their last ticks, and what they kept since the last tick archived,
    ready to write (their own keys only); each node is asked until it answers, up to
    ``ASK_AGAIN_FOR_S`` (or ``stop``)."""
    out: list[Pending] = []
    waiting = list(nodes)
    deadline = time.monotonic() + ASK_AGAIN_FOR_S
    while True:
        for node in list(waiting):
            got = fetch(transport, mission, node, FETCH_TIMEOUT_S)
            for why in got.malformed:
                log.warning("%s answered what it sent lately with a malformed reply: %s", node,
                            why)
            if got.answered:
                waiting.remove(node)
                out += [prepare_raw(s.key, s.type_name, s.payload) for s in got.samples]
        if not waiting or time.monotonic() > deadline or stop.wait(0.5):
            break
    if waiting:
        log.error("%s never answered what they kept within %.0f s: what they sent while the "
                  "recorder could not hear them is counted lost", ", ".join(waiting),
                  ASK_AGAIN_FOR_S)
    log.warning("took %d messages the nodes kept of their last ticks", len(out))
    return out


if __name__ == "__main__":
    raise SystemExit(main())
