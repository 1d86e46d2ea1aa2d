"""Ground station process (central agent): ``python -m ground --scenario F``."""

from __future__ import annotations

import argparse

from ground.station import ground_executive
from interfaces.contracts import topics
from interfaces.runtime.cli import add_node_args, run_participant


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ground", description=__doc__)
    add_node_args(parser)
    return run_participant(parser.parse_args(argv), topics.GROUND, ground_executive)


if __name__ == "__main__":
    raise SystemExit(main())
