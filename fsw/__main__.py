"""Flight software process of one spacecraft: ``python -m fsw --spacecraft N --scenario F``."""

from __future__ import annotations

import argparse

from interfaces.contracts import topics
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topology import topology
from interfaces.runtime.assembly import executive_of
from interfaces.runtime.bus import Bus
from interfaces.runtime.cli import add_node_args, run_participant
from interfaces.runtime.executive import Executive
from links.channel import ChannelModel


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m fsw", description=__doc__)
    parser.add_argument("--spacecraft", type=int, required=True, help="spacecraft id (1-based)")
    add_node_args(parser)
    args = parser.parse_args(argv)
    node = topics.sc_node(args.spacecraft)

    def build(bus: Bus, scenario: Scenario) -> Executive:
        try:
            return executive_of(topology(scenario).node(node), bus, scenario)
        except ValueError as e:
            raise SystemExit(f"spacecraft {args.spacecraft} is not in this scenario: {e}") from e

    return run_participant(args, node, build, ChannelModel.of)


if __name__ == "__main__":
    raise SystemExit(main())
