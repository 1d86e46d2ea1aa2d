"""Flight software process of one spacecraft: ``python -m fsw --spacecraft N --scenario F``."""

from __future__ import annotations

import argparse
from functools import partial

from fsw.spacecraft import spacecraft_executive
from interfaces.contracts import topics
from interfaces.contracts.scenario import Scenario
from interfaces.runtime.bus import Bus
from interfaces.runtime.cli import add_node_args, run_participant
from interfaces.runtime.executive import Executive


def _build(spacecraft: int, bus: Bus, scenario: Scenario) -> Executive:
    if spacecraft > scenario.observers.count:
        raise SystemExit(f"spacecraft {spacecraft} not in scenario "
                         f"({scenario.observers.count} observers)")
    return spacecraft_executive(bus, scenario, spacecraft)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m fsw", description=__doc__)
    parser.add_argument("--spacecraft", type=int, required=True, help="spacecraft id (1-based)")
    add_node_args(parser)
    args = parser.parse_args(argv)
    return run_participant(args, topics.sc_node(args.spacecraft), partial(_build, args.spacecraft))


if __name__ == "__main__":
    raise SystemExit(main())
