"""Sim process (time master, truth, sensors): ``python -m sim --scenario F --participants ...``."""

from __future__ import annotations

import argparse

from interfaces.contracts import topics
from interfaces.contracts.topology import topology
from interfaces.runtime.bundle_out import BundleOut
from interfaces.runtime.bus import Bus
from interfaces.runtime.cli import add_node_args, open_zenoh, start_node
from interfaces.runtime.heap import frozen_heap
from interfaces.runtime.recent import depth_for
from sim.lockstep import LinkAwait
from sim.node import SimNode


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m sim", description=__doc__)
    add_node_args(parser)
    parser.add_argument("--no-ground", action="store_true",
                        help="do not wait for a ground node (spacecraft only)")
    parser.add_argument("--realtime", type=float, metavar="SPEED",
                        help="run at most SPEED times real time, still in lockstep "
                             "(sim/pacing.py)")
    parser.add_argument("--hard-deadline", action="store_true",
                        help="with --realtime: wait for answers only until the next tick is "
                             "due; a late node misses the tick (hardware-in-the-loop style)")
    parser.add_argument("--hold-lost", type=float, default=0.0, metavar="SECONDS",
                        help="wait up to SECONDS of wall time for a lost participant to come "
                             "back (its restart) before the next tick (default: fly on)")
    parser.add_argument("--await-link", action="append", default=[], type=LinkAwait.parse,
                        metavar="lost|back:NODES:T_S",
                        help="a rehearsal's link cut or restored after the tick at T_S: held "
                             "for until NODES are gone or back (docs/hosts.md); repeatable")
    args = parser.parse_args(argv)
    start = start_node(args, topics.SIM)
    log, scenario = start.log, start.scenario
    participants = topology(scenario, ground=not args.no_ground).participants
    bus = Bus(topics.SIM, start.mission, open_zenoh(args),
              recent_ticks=depth_for(scenario.rates.ticks_per("mid")))
    BundleOut.share([bus], start.mission)
    try:
        sim = SimNode(bus, scenario, participants, realtime_speed=args.realtime,
                      hard_deadline=args.hard_deadline, hold_lost_s=args.hold_lost, log=log,
                      stop=start.stop,
                      link_awaits=tuple(sorted(args.await_link, key=lambda a: a.t_s)))
        bus.watch_alive(sim.on_liveness)
        bus.serve_schemas()
        bus.serve_recent()
        bus.declare_alive()
        try:
            sim.wait_for_participants(scenario.sim.startup_timeout_s)
        except TimeoutError as e:
            log.error("%s", e)
            return 2
        start.stop.wait(0.5)  # let the last subscriptions propagate through the mesh
        with frozen_heap():  # what the start made is not walked by every full collection
            return 0 if sim.run() else 1
    finally:
        bus.close()


if __name__ == "__main__":
    raise SystemExit(main())
