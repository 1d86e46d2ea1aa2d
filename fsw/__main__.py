"""Flight software process of one spacecraft or of several that share it (stepping together):
``python -m fsw --spacecraft N [M ...] --scenario F``."""

from __future__ import annotations

import argparse
import sys
from functools import partial

from interfaces.contracts import topics
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topology import topology
from interfaces.runtime.assembly import executive_of
from interfaces.runtime.bus import Bus
from interfaces.runtime.cli import add_node_args, run_participants
from interfaces.runtime.executive import Executive
from interfaces.runtime.kernels import compile_kernels
from links.channel import ChannelModel


def _build(bus: Bus, scenario: Scenario) -> Executive:
    """The executive of the spacecraft whose bus is ``bus``."""
    try:
        return executive_of(topology(scenario).node(bus.node), bus, scenario)
    except ValueError as e:
        raise SystemExit(f"{bus.node} is not in this scenario: {e}") from e


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m fsw", description=__doc__)
    parser.add_argument("--spacecraft", type=int, nargs="+", required=True, metavar="N",
                        help="spacecraft id(s) (1-based); several share this process, each "
                             "with its own account ('{node}' in --zenoh-config)")
    add_node_args(parser)
    args = parser.parse_args(argv)
    if len(set(args.spacecraft)) != len(args.spacecraft):
        parser.error(f"--spacecraft names a spacecraft twice: {args.spacecraft}")
    if len(args.spacecraft) > 1 and args.zenoh_config and "{node}" not in args.zenoh_config:
        parser.error("several spacecraft need an account each: put '{node}' in --zenoh-config")
    nodes = [topics.sc_node(i) for i in args.spacecraft]
    compile_kernels(partial(print, file=sys.stderr))  # loaded before the first tick
    return run_participants(args, nodes, _build, ChannelModel.of)


if __name__ == "__main__":
    raise SystemExit(main())
