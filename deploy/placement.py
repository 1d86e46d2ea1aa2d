"""Where a Zenoh run's processes go (docs/hosts.md): each account's client configuration, each
process's network namespace, the routers, and which nodes share a process.

On one host (the default) every process is a client of the run's one router, on this
machine's network.  Across hosts (``--hosts``) each host runs a router of its own and its nodes
are clients of it; rehearsed (``--rehearse``), each host's processes run in its namespace.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from deploy.access import TLM_ACCOUNT, RunAccess
from deploy.host_map import HostMap
from interfaces.contracts.topology import ROUTER, Hosting, NodeProcess, Topology, hosting

if TYPE_CHECKING:  # its certificates import cryptography: only across hosts
    from deploy.host_access import HostAccess


@dataclass(frozen=True)
class RouterPlace:
    """A router process: its name (``router``, or ``router-<host>``), configuration and
    namespace."""

    name: str
    config: Path
    endpoint: str
    netns: str | None = None


@dataclass(frozen=True)
class Placement:
    """See the module docstring."""

    routers: tuple[RouterPlace, ...]
    watch_config: Path
    """the launcher's own client configuration (the read-only account, at the hub)"""
    configs: dict[str, Path]
    """account (a node, ``recorder``, ``tlm``) -> its client configuration"""
    namespaces: dict[str, str] = field(default_factory=dict)
    """node or service -> the namespace it runs in (none: this one)"""
    host_map: HostMap | None = None

    def config(self, account: str) -> Path:
        """``account``'s client configuration; a clear error when it has none."""
        path = self.configs.get(account)
        if path is None or not path.is_file():
            raise FileNotFoundError(f"no account {account!r} in this run's access files")
        return path

    def netns(self, name: str) -> str | None:
        """The namespace the node or service ``name`` runs in."""
        return self.namespaces.get(name)

    def processes(self, topo: Topology, mode: Hosting, processes: int,
                  alone: Collection[str] = ()) -> tuple[NodeProcess, ...]:
        """The processes of the lockstep nodes: on one host, ``hosting`` over its cores;
        across hosts, each host's spacecraft in one process (``packed``) or each alone, the
        ground alone."""
        if self.host_map is None:
            return hosting(topo, mode, processes, alone)
        return host_processes(self.host_map, topo, mode)


def host_processes(host_map: HostMap, topo: Topology, mode: Hosting) -> tuple[NodeProcess, ...]:
    """The processes of the lockstep nodes across hosts: each host's spacecraft in one process
    (``packed``) or each alone, the ground alone."""
    out: list[NodeProcess] = []
    for h in host_map.hosts:
        nodes = [topo.node(n) for n in h.nodes if n in topo.participants]
        spacecraft = tuple(n for n in nodes if n.spacecraft is not None)
        if spacecraft and mode == "packed":
            out.append(NodeProcess(spacecraft))
        else:
            out += [NodeProcess((n,)) for n in spacecraft]
        out += [NodeProcess((n,)) for n in nodes if n.spacecraft is None]
    return tuple(out)


def one_host(access: RunAccess) -> Placement:
    """The default: one router, every process here."""
    configs = {p.stem: p for p in access.directory.glob("*.json5") if p.name != "router.json5"}
    return Placement((RouterPlace(ROUTER.name, access.router_config, access.endpoint),),
                     access.client_config(TLM_ACCOUNT), configs)


def across_hosts(access: HostAccess, host_map: HostMap,
                 namespaces: dict[str, str] | None = None) -> Placement:
    """A router per host of ``host_map``; ``namespaces``: host -> namespace when rehearsed."""
    namespaces = namespaces or {}
    routers = tuple(RouterPlace(f"{ROUTER.name}-{h.name}", access.hosts[h.name].router_config,
                                f"tls/{h.address}:{host_map.port}", namespaces.get(h.name))
                    for h in host_map.hosts)
    configs = {n: access.hosts[h.name].client_config(n) for h in host_map.hosts
               for n in h.nodes}
    placed = {n: namespaces[h.name] for h in host_map.hosts for n in h.nodes
              if h.name in namespaces}
    return Placement(routers, access.tlm_config, configs, placed, host_map)
