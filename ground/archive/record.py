"""Recorder process: ``python -m ground.archive.record --scenario F --out run.mcap``.

Subscribes to every key of the mission and archives each message, with its JSON schema, in an
MCAP file (Foxglove opens it).  SIGINT/SIGTERM finish the file cleanly (summary and footer).
"""

from __future__ import annotations

import argparse
import functools
import importlib.metadata
import subprocess
import time
from pathlib import Path

from ground.archive.recorder import McapRecorder
from interfaces import topics
from interfaces.cli import (
    add_node_args,
    load_node_scenario,
    mission_of,
    open_zenoh,
    setup_logging,
    stop_on_signals,
)
from interfaces.scenario import Scenario


@functools.cache
def software_version() -> str:
    """The package version, with the git commit of the checkout it runs from when there is
    one (``0.1.0+g46a41bc``, ``-dirty`` with uncommitted changes)."""
    try:
        version = importlib.metadata.version("insp-fdir")
    except importlib.metadata.PackageNotFoundError:
        version = "unknown (not installed)"
    repo = Path(__file__).resolve().parent.parent
    try:
        commit = subprocess.run(["git", "-C", str(repo), "describe", "--always", "--dirty",
                                 "--exclude", "*"], capture_output=True, text=True, timeout=10,
                                check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return version
    return f"{version}+g{commit}" if commit else version


def run_metadata(scenario: Scenario, transport: str, scenario_toml: str) -> dict[str, dict[str, str]]:
    """MCAP metadata records of a run: what ran, with which seed and software."""
    return {
        "run": {"scenario": scenario.name, "seed": str(scenario.seed), "transport": transport,
                "duration_s": str(scenario.duration_s), "software_version": software_version(),
                "started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())},
        "scenario": {"toml": scenario_toml, "resolved_json": scenario.model_dump_json()},
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ground.archive.record", description=__doc__)
    add_node_args(parser)
    parser.add_argument("--out", required=True, help="MCAP file to write")
    parser.add_argument("--transport-name", default="zenoh", help="recorded in the metadata")
    args = parser.parse_args(argv)
    log = setup_logging(args.log_level, "recorder")
    scenario = load_node_scenario(args)
    mission = mission_of(args, scenario)
    stop = stop_on_signals()
    with open(args.scenario, encoding="utf-8") as f:
        meta = run_metadata(scenario, args.transport_name, f.read())
    rec = McapRecorder(args.out, meta)
    transport = open_zenoh(args)
    try:
        transport.subscribe(topics.mission_wildcard(mission), rec.record)
        transport.declare_alive("recorder", topics.recorder_token(mission))
        log.info("recording %s to %s", topics.mission_wildcard(mission), args.out)
        while not stop.wait(2.0):
            rec.flush()  # a killed recorder loses at most the last 2 s
    finally:
        transport.close()  # no callback can write after this
        rec.close()
    log.info("archive closed: %d messages recorded, %d invalid", rec.recorded, rec.invalid)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
