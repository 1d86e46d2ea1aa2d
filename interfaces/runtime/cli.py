"""Command-line plumbing shared by the node processes (sim, fsw, ground, recorder)."""

from __future__ import annotations

import argparse
import logging
import queue
import signal
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from interfaces.contracts import topics
from interfaces.contracts.messages import Tick
from interfaces.contracts.scenario import Scenario, ScenarioError, load_scenario
from interfaces.contracts.topology import topology
from interfaces.runtime.arguments import add_log_level, endpoint, mission_name
from interfaces.runtime.blas_threads import one_blas_thread
from interfaces.runtime.bundle_out import BundleOut
from interfaces.runtime.bus import Bus
from interfaces.runtime.cds import CriticalDataStore
from interfaces.runtime.executive import Executive, TickClient, serve_together
from interfaces.runtime.fleet import fleets_of
from interfaces.runtime.heap import frozen_heap
from interfaces.runtime.link_stage import LinkStageFactory
from interfaces.runtime.recent import depth_for
from interfaces.runtime.restart import resume_together
from interfaces.runtime.signals import signal_setter
from interfaces.runtime.zenoh_transport import (
    DEFAULT_ENDPOINT,
    SharedReceiver,
    ZenohSettings,
    ZenohTransport,
)


def add_node_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scenario", required=True, help="scenario TOML file")
    parser.add_argument("--mission", type=mission_name,
                        help="key-space name (default: the scenario name)")
    parser.add_argument("--seed", type=int, help="override the scenario seed")
    parser.add_argument("--duration", type=float, help="override duration_s (s)")
    parser.add_argument("--connect", default=DEFAULT_ENDPOINT, type=endpoint,
                        help=f"Zenoh endpoint to join (default {DEFAULT_ENDPOINT})")
    parser.add_argument("--zenoh-config",
                        help="Zenoh JSON5 config file (overrides --connect); in a process "
                             "hosting several nodes, '{node}' in it is each node's name "
                             "(its account: access/{node}.json5)")
    add_log_level(parser)
    parser.add_argument("--cds", type=Path, metavar="DIR",
                        help="keep this node's critical-data store in DIR (made by the launcher "
                             "with the run's key) and restore from it when started again "
                             "(interfaces/runtime/cds.py)")


def load_node_scenario(args: argparse.Namespace) -> Scenario:
    """The scenario with command-line overrides; exits with a readable message if invalid."""
    try:
        return load_scenario(args.scenario).with_overrides(args.seed, args.duration)
    except ScenarioError as e:
        raise SystemExit(str(e)) from None


def mission_of(args: argparse.Namespace, scenario: Scenario) -> str:
    return str(args.mission or scenario.name)


def open_zenoh(args: argparse.Namespace, node: str = "",
               shared: SharedReceiver | None = None) -> ZenohTransport:
    """A Zenoh session of ``node`` (its own account: ``{node}`` in ``--zenoh-config``),
    receiving through ``shared`` if given (the nodes of one process)."""
    config = args.zenoh_config.replace("{node}", node) if args.zenoh_config else None
    return ZenohTransport(ZenohSettings(connect=(args.connect,), config_file=config),
                          shared=shared, node=node)


def setup_logging(level: str, name: str) -> logging.Logger:
    """Logging of process ``name``; a process hosting several nodes (``sc1+sc2``) names each
    line's logger (``insp.sc2.guidance``)."""
    which = "[%(name)s] " if "+" in name else ""
    logging.basicConfig(level=getattr(logging, level.upper(), logging.INFO),
                        format=f"%(asctime)s {name:>7} %(levelname)s {which}%(message)s",
                        datefmt="%H:%M:%S")
    return logging.getLogger(f"insp.{name}")


@dataclass(frozen=True)
class NodeStart:
    """What every node process starts with: its logger, the scenario with the command line's
    overrides, the mission (key-space) name, and the event its signals set."""

    log: logging.Logger
    scenario: Scenario
    mission: str
    stop: threading.Event


def start_node(args: argparse.Namespace, name: str) -> NodeStart:
    """Logging as ``name``, the scenario (exits with a readable message if invalid), the mission
    name and the stop event of a node process started with :func:`add_node_args`'s options;
    its BLAS on one thread (``interfaces.runtime.blas_threads``)."""
    one_blas_thread()
    log = setup_logging(args.log_level, name)
    scenario = load_node_scenario(args)
    return NodeStart(log, scenario, mission_of(args, scenario), stop_on_signals())


def stop_on_signals() -> threading.Event:
    """An event set by SIGINT/SIGTERM, so a node finishes its loop and closes cleanly."""
    stop = threading.Event()
    signal.signal(signal.SIGINT, signal_setter(stop))
    signal.signal(signal.SIGTERM, signal_setter(stop))
    return stop


def run_participant(
    args: argparse.Namespace,
    node: str,
    build: Callable[[Bus, Scenario], Executive],
    links: LinkStageFactory,
) -> int:
    """Main loop of a process hosting the one lockstep node ``node`` (:func:`run_participants`)."""
    return run_participants(args, [node], build, links)


def run_participants(
    args: argparse.Namespace,
    nodes: list[str],
    build: Callable[[Bus, Scenario], Executive],
    links: LinkStageFactory,
) -> int:
    """Main loop of a process hosting the lockstep nodes ``nodes`` (spacecraft or the ground)
    over Zenoh.

    Each node joins the network with its own account and session (they receive through one
    ``SharedReceiver``: what several of them read comes once), and its executive is wired
    on its own bus (``build(bus, scenario)``, with the link stage ``links(node, scenario)``);
    nodes running the same apps step together (``interfaces/runtime/fleet.py``).  Each is
    restored from its critical-data store when started again (``--cds``), serves the message
    schemas and what it sent lately, and announces itself.  Ticks run until the sim finishes
    (exit 0), the sim disappears (exit 3) or a signal stops the process (exit 0).  Every Zenoh
    session is always closed."""
    start = start_node(args, "+".join(nodes))
    buses: list[Bus] = []
    receiver = SharedReceiver() if len(nodes) > 1 else None
    try:
        for node in nodes:
            buses.append(Bus(node, start.mission, open_zenoh(args, node, receiver),
                             channel=links(node, start.scenario),
                             recent_ticks=depth_for(start.scenario.rates.ticks_per("mid"))))
        BundleOut.share(buses, start.mission)  # sent on its first node's session
        shared: queue.Queue[tuple[TickClient, int, Tick] | None] = queue.Queue()
        clients = [TickClient(build(bus, start.scenario), tick_queue=shared) for bus in buses]
        _step_together(clients, start.scenario)
        for client in clients:
            client.executive.bus.serve_recent()
        if args.cds is not None:
            _restore(clients, args.cds, start)
        for client in clients:
            _join(client)
        start.log.info("ready")
        with frozen_heap():  # what the start made is not walked by every full collection
            serve_together(clients, start.stop)
        lost = [c.executive.bus.node for c in clients if c.sim_lost and not c.finished.is_set()]
        if lost:
            start.log.error("sim lost before the end of the run (%s)", ", ".join(lost))
            return 3
        return 0
    finally:
        for bus in buses:
            bus.close()


def _step_together(clients: list[TickClient], scenario: Scenario) -> None:
    """The clients of one process whose nodes run the same apps step together."""
    if len(clients) < 2:
        return
    topo = topology(scenario)
    executives = {c.executive.bus.node: c.executive for c in clients}
    fleets = fleets_of([topo.node(n) for n in executives], executives)
    for client in clients:
        fleet = fleets[client.executive.bus.node]
        if len(fleet.members) > 1:
            client.fleet = fleet.take


def _restore(clients: list[TickClient], cds: Path, start: NodeStart) -> None:
    """The process's nodes restored together from their critical-data stores in ``cds``,
    when started again (``interfaces.runtime.restart.resume_together``)."""
    resume_together([(c, CriticalDataStore.open(cds, start.mission, c.executive.bus.node,
                                                start.scenario)) for c in clients],
                    [topics.SIM, *topology(start.scenario).participants], start.log)


def _join(client: TickClient) -> None:
    """``client``'s node watching the others' liveliness, serving its schemas, and
    announced."""
    bus = client.executive.bus
    bus.watch_alive(client.on_liveness)
    bus.serve_schemas()
    bus.declare_alive()
