"""Recorder process: ``python -m ground.archive.record --scenario F --out run.mcap``.

Subscribes to every key of the mission and archives each message, with its JSON schema, in an
MCAP file (Foxglove opens it).  SIGINT/SIGTERM finish the file cleanly (summary and footer).

When ``--out`` exists already (the recorder was restarted, by the launcher's
``--restart-on-crash``, with the same command), it continues the run's archive in the next
free segment, ``run-1.mcap``, ``run-2.mcap``, ... (``ground/archive/segments.py``): never over
what exists, with the same run metadata and a ``segment`` record.  Restarted, it first records
what every node still keeps of its last ticks (``interfaces.runtime.recent``): the chunk in
progress when it was killed, at most one ω_mid period of sim time (a chunk is closed at every
period), is among it.  It declares its liveliness token (``topics.recorder_token``) once
subscribed, ready to record (the sim holds the clock until then).
"""

from __future__ import annotations

import argparse
import logging

from ground.archive.metadata import run_metadata
from ground.archive.recorder import McapRecorder
from ground.archive.segments import claim_segment, with_segment
from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.topology import topology
from interfaces.runtime.cli import add_node_args, open_zenoh, start_node
from interfaces.runtime.recent import parse_reply
from interfaces.runtime.transport import RawHandler
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
    try:
        transport.subscribe(topics.mission_wildcard(mission),
                            _flushing(rec, cat.TICK.key(mission),
                                      start.scenario.rates.ticks_per("mid")))
        if segment:  # restarted: what the nodes still keep of their last ticks
            _take_recent(transport, rec, mission, [topics.SIM, *topology(start.scenario)
                                                   .participants], log)
        transport.declare_alive("recorder", topics.recorder_token(mission))
        log.info("recording %s to %s", topics.mission_wildcard(mission), path)
        while not start.stop.wait(2.0):
            rec.flush()  # and at least every 2 s of wall time
    finally:
        transport.close()  # no callback can write after this
        rec.close()
    log.info("archive closed: %d messages recorded, %d invalid", rec.recorded, rec.invalid)
    return 0


def _flushing(rec: McapRecorder, tick_key: str, every: int) -> RawHandler:
    """``rec.record``, closing the chunk in progress at every ``every``-th tick (each ω_mid
    period of sim time): a killed recorder loses at most the period it was writing, which the
    nodes still keep of their last ticks (``interfaces.runtime.recent``) for its restart."""
    ticks = [0]

    def record(key: str, type_name: str, payload: bytes) -> None:
        rec.record(key, type_name, payload)
        if key == tick_key:
            ticks[0] += 1
            if ticks[0] % every == 0:
                rec.flush()

    return record


def _take_recent(transport: ZenohTransport, rec: McapRecorder, mission: str,
                 nodes: list[str], log: logging.Logger) -> None:
    """Record what ``nodes`` sent in their last ticks (the restarted recorder's first act: the
    messages its predecessor had not written yet; the archive reader keeps a message twice
    recorded once)."""
    taken = 0
    for node in nodes:
        for _key, payload in transport.query(topics.recent_queryable(mission, node)):
            try:
                samples = parse_reply(payload)
            except ValueError as e:
                log.warning("%s answered what it sent lately with a malformed reply: %s", node, e)
                continue
            for s in samples:
                if topics.node_of_key(s.key) == node:
                    rec.record(s.key, s.type_name, s.payload)
                    taken += 1
    log.warning("restarted: recorded %d messages the nodes kept of their last ticks", taken)


if __name__ == "__main__":
    raise SystemExit(main())
