"""Recorder process: ``python -m ground.archive.record --scenario F --out run.mcap``.

Subscribes to every key of the mission and archives each message, with its JSON schema, in an
MCAP file (Foxglove opens it).  SIGINT/SIGTERM finish the file cleanly (summary and footer).

When ``--out`` exists already (the recorder was restarted, by the launcher's
``--restart-on-crash``, with the same command), it continues the run's archive in the next
free segment, ``run-1.mcap``, ``run-2.mcap``, ... (``ground/archive/segments.py``): never over
what exists, with the same run metadata and a ``segment`` record.  It declares its liveliness
token (``topics.recorder_token``) once subscribed, ready to record.
"""

from __future__ import annotations

import argparse

from ground.archive.metadata import run_metadata
from ground.archive.recorder import McapRecorder
from ground.archive.segments import claim_segment, with_segment
from interfaces.contracts import topics
from interfaces.runtime.cli import add_node_args, open_zenoh, start_node


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
        transport.subscribe(topics.mission_wildcard(mission), rec.record)
        transport.declare_alive("recorder", topics.recorder_token(mission))
        log.info("recording %s to %s", topics.mission_wildcard(mission), path)
        while not start.stop.wait(2.0):
            rec.flush()  # a killed recorder loses at most the last 2 s
    finally:
        transport.close()  # no callback can write after this
        rec.close()
    log.info("archive closed: %d messages recorded, %d invalid", rec.recorded, rec.invalid)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
