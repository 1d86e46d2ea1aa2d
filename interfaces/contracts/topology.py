"""The constellation's topology, declared once (docs/architecture.md, "Processes"): which
nodes take part in a run, which apps each runs, how each node's executive is assembled, and
which process holds what.

Read by the in-process runner (``deploy/inproc.py``: every node in one process), the
multi-process launcher (``deploy/run_constellation.py``: one process per node, plus the
router, the recorder and the sim), replay (``harness/replay.py``: the ground node alone),
the spacecraft and station processes (``python -m fsw``, ``python -m ground``) and the sim
(the participants it waits for).

Apps and builders are named ``"module:attribute"`` so that this contract imports no flight,
sim or ground code; ``interfaces/runtime/assembly.py`` resolves them.  Each app declares its
own rate group, inputs and outputs (``interfaces/runtime/app.py``); the order here is the
execution order within a rate group.  ``python -m interfaces.contracts.topology`` prints the
default scenario's topology; with ``--graph`` the dataflow, every topic with its publishers and
readers (``interfaces/contracts/dataflow.py``), with ``--mermaid`` its picture's block and with
``--write-doc`` that block rewritten in docs/architecture.md.
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Collection
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from interfaces.contracts import dataflow, topics
from interfaces.contracts.apps import (
    GROUND_APPS,
    NEIGHBOUR_APPS,
    ONBOARD_FDIR_APPS,
    SPACECRAFT_APPS,
)
from interfaces.contracts.scenario import Scenario, load_scenario

REPO = Path(__file__).resolve().parents[2]

@dataclass(frozen=True)
class Node:
    """A lockstep participant: one executive running ``apps``, built by ``executive``
    (``"module:function"`` taking the node, its bus and the scenario), its random stream
    named ``rng`` (``interfaces/contracts/rng.py``), and its process started by
    ``python -m module *args`` when it runs in a process of its own."""

    name: str
    apps: tuple[str, ...]
    executive: str
    rng: tuple[str, int]
    module: str
    args: tuple[str, ...] = ()
    spacecraft: int | None = None

    @property
    def command(self) -> list[str]:
        """The Python arguments starting its own process (the run's common ones aside)."""
        return ["-m", self.module, *self.args]


@dataclass(frozen=True)
class Service:
    """A process that is not a lockstep participant: ``python -m module``."""

    name: str
    module: str

    @property
    def command(self) -> list[str]:
        return ["-m", self.module]


ROUTER = Service("router", "deploy.router")
"""The run's Zenoh router (multi-process runs only)."""
RECORDER = Service("recorder", "ground.archive.record")
"""The archive's recorder (in one process: a tap on the in-process network)."""
SIM = Service(topics.SIM, "sim")
"""The time master and hardware stand-in."""


def spacecraft_node(spacecraft: int, onboard_fdir: bool = False,
                    neighbours: bool = False) -> Node:
    """Spacecraft ``spacecraft``'s flight software (1-based), with the agent-level FDIR app
    when ``onboard_fdir`` and the neighbours' FDIR app when ``neighbours``."""
    apps = (SPACECRAFT_APPS + (ONBOARD_FDIR_APPS if onboard_fdir else ())
            + (NEIGHBOUR_APPS if neighbours else ()))
    return Node(topics.sc_node(spacecraft), apps, "fsw.spacecraft:executive",
                ("fsw", spacecraft), "fsw", ("--spacecraft", str(spacecraft)), spacecraft)


GROUND = Node(topics.GROUND, GROUND_APPS, "interfaces.runtime.assembly:build_executive",
              ("ground", 0), "ground")
"""The ground station (central agent)."""


@dataclass(frozen=True)
class Topology:
    """A run's lockstep participants (the spacecraft in order, then the ground if any), and
    the services beside them."""

    nodes: tuple[Node, ...]
    services: tuple[Service, ...] = (ROUTER, RECORDER, SIM)

    @property
    def participants(self) -> list[str]:
        """The node names the sim waits for each tick."""
        return [n.name for n in self.nodes]

    def node(self, name: str) -> Node:
        """The node called ``name``; a clear error when the run has none."""
        for n in self.nodes:
            if n.name == name:
                return n
        raise ValueError(f"no node {name!r} in this run (nodes: {', '.join(self.participants)})")


def topology(scenario: Scenario, ground: bool = True) -> Topology:
    """The topology of a run of ``scenario``: one node per observer, and the ground unless
    ``ground`` is False (spacecraft only)."""
    onboard, neighbours = scenario.onboard_fdir.enabled, scenario.neighbours.enabled
    nodes = [spacecraft_node(i, onboard, neighbours)
             for i in range(1, scenario.observers.count + 1)]
    return Topology(tuple(nodes + ([GROUND] if ground else [])))


Hosting = Literal["packed", "one-per-process"]
"""How a multi-process run puts its lockstep nodes in processes: ``packed`` (the default on
one host) shares the spacecraft among as many processes as the host has cores, stepping
together (``interfaces/runtime/fleet.py``); ``one-per-process``, every node alone, as on
separate computers.  The ground is always alone."""


@dataclass(frozen=True)
class NodeProcess:
    """One process of a multi-process run and the lockstep nodes it hosts (one account, bus
    and Zenoh session each): named for its node when alone, else for them all
    (``sc1+sc2+sc3``)."""

    nodes: tuple[Node, ...]

    def __post_init__(self) -> None:
        if not self.nodes:
            raise ValueError("a process needs at least one node")
        if len({(n.module, n.args[:1]) for n in self.nodes}) != 1:
            raise ValueError("the nodes of one process must start the same way, got "
                             + ", ".join(" ".join(n.command) for n in self.nodes))

    @property
    def name(self) -> str:
        return "+".join(n.name for n in self.nodes)

    @property
    def command(self) -> list[str]:
        """The Python arguments starting it: its nodes' module, and their values of its one
        option together (``-m fsw --spacecraft 1 2 3``)."""
        first = self.nodes[0]
        if len(self.nodes) == 1:
            return first.command
        return ["-m", first.module, *first.args[:1], *(n.args[1] for n in self.nodes)]


def hosting(topo: Topology, mode: Hosting, processes: int,
            alone: Collection[str] = ()) -> tuple[NodeProcess, ...]:
    """The processes of a multi-process run of ``topo`` (:data:`Hosting`): ``packed``, the
    spacecraft in ``processes`` processes of consecutive ids (sizes differing by one at most),
    the nodes named in ``alone`` (run elsewhere) and the ground each alone."""
    if processes < 1:
        raise ValueError(f"processes must be at least 1, got {processes}")
    packable = [n for n in topo.nodes if n.spacecraft is not None and n.name not in alone]
    singles = [NodeProcess((n,)) for n in topo.nodes if n not in packable]
    if mode == "one-per-process" or not packable:
        return tuple(NodeProcess((n,)) for n in topo.nodes)
    count = min(processes, len(packable))
    ends = [round(len(packable) * (i + 1) / count) for i in range(count)]
    blocks = [NodeProcess(tuple(packable[a:b])) for a, b in zip([0, *ends], ends, strict=False)]
    return tuple(blocks + singles)


def describe(topo: Topology) -> str:
    """The topology as a table: each process, what it runs and how it starts."""
    rows = [(s.name, "-", "python " + " ".join(s.command)) for s in topo.services]
    rows += [(n.name, ", ".join(a.split(":")[1] for a in n.apps), "python " + " ".join(n.command))
             for n in topo.nodes]
    width = [max(len(r[i]) for r in rows) for i in range(2)]
    return "\n".join(f"{r[0]:<{width[0]}}  {r[1]:<{width[1]}}  {r[2]}" for r in rows)


DECLARATIONS = "interfaces.runtime.assembly:declarations"
"""What gathers the apps' declarations for the dataflow, loaded by name (as the apps are)."""


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m interfaces.contracts.topology",
                                     description="The default scenario's topology.")
    what = parser.add_mutually_exclusive_group()
    what.add_argument("--graph", action="store_true",
                      help="the dataflow: every topic, publishers → readers, with rate groups")
    what.add_argument("--mermaid", action="store_true",
                      help="the dataflow picture's block, as docs/architecture.md holds it")
    what.add_argument("--write-doc", action="store_true",
                      help="rewrite that block in docs/architecture.md")
    return parser


def _dataflow(args: argparse.Namespace, doc: Path) -> str:
    """What ``--graph``, ``--mermaid`` or ``--write-doc`` prints (and writes)."""
    module, _, name = DECLARATIONS.partition(":")
    flows = dataflow.graph(getattr(importlib.import_module(module), name)())
    if args.graph:
        return dataflow.edges(flows) + "\n"
    if args.mermaid:
        return dataflow.doc_block(flows)
    changed = dataflow.write_doc(doc, flows)
    return f"{doc}: {'rewritten' if changed else 'already current'}\n"


def main(argv: list[str] | None = None, doc: Path = REPO / "docs" / "architecture.md") -> None:
    """``python -m interfaces.contracts.topology [--graph | --mermaid | --write-doc]``; ``doc``:
    the document ``--write-doc`` rewrites."""
    args = _parser().parse_args(argv)
    if args.graph or args.mermaid or args.write_doc:
        print(_dataflow(args, doc), end="")
    else:
        print(describe(topology(load_scenario(REPO / "deploy" / "scenarios" / "default.toml"))))


if __name__ == "__main__":
    main()
