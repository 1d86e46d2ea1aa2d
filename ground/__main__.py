"""Ground station process (central agent): ``python -m ground --scenario F``."""

from __future__ import annotations

import argparse
import sys
from functools import partial

from interfaces.contracts import topics
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topology import topology
from interfaces.runtime.assembly import executive_of
from interfaces.runtime.bus import Bus
from interfaces.runtime.cli import add_node_args, run_participant
from interfaces.runtime.executive import Executive
from interfaces.runtime.kernels import compile_kernels
from links.channel import ChannelModel


def _build(bus: Bus, scenario: Scenario) -> Executive:
    return executive_of(topology(scenario).node(topics.GROUND), bus, scenario)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ground", description=__doc__)
    add_node_args(parser)
    args = parser.parse_args(argv)
    compile_kernels(partial(print, file=sys.stderr))  # loaded before the first tick
    return run_participant(args, topics.GROUND, _build, ChannelModel.of)


if __name__ == "__main__":
    raise SystemExit(main())
