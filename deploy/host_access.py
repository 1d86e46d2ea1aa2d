"""Who may do what across hosts (docs/hosts.md): a router per host, each with its own
certificate from the run's authority, the hub's (the ground host's) the one the others link to
over TLS, and the access rules of ``deploy.access`` on every router.

Written under ``<out>/access/<host>/`` (owner-only), one folder per host, all that host needs:

* ``router.json5``: listens on ``tcp/127.0.0.1:<port>`` (its own nodes) and
  ``tls/<address>:<port>`` (the other hosts); a host other than the hub connects to the hub
  over TLS with an account of its own (``router-<host>``) and verifies the hub's certificate;
* ``router.pem`` / ``router.key``: its certificate, named ``router-<host>``, and key;
  ``authority.pem``: the run's authority;
* ``users.txt``: the accounts that may log in to it: its own nodes' and, on the hub, the
  read-only ``tlm`` and the other routers';
* ``<node>.json5``: each of its nodes' client configuration (its host's router, on loopback).

The hub lets another host's router publish only what that host's nodes may
(``access_control(relays=...)``); a router trusts the hub's link by the name of the hub's
certificate, which it verified.  ``<out>/access/tlm.json5`` watches the run from anywhere on
the hosts' network (TLS to the hub).
"""

from __future__ import annotations

import json
import secrets
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from deploy.access import (
    NO_SCOUTING,
    TLM_ACCOUNT,
    Account,
    TlsFiles,
    access_control,
    account_file,
    client_config,
    write_private,
)
from deploy.certificates import Authority, write_authority, write_certificate
from deploy.host_map import HostMap, HostSpec

RECONNECT_MS = 500
"""How often a router whose link to the hub broke tries again, ms (a restored link is back
within about this)."""


def router_name(host: HostSpec) -> str:
    """A host's router's name: its certificate's common name and, but for the hub's, the
    account it logs in to the hub with."""
    return f"router-{host.name}"


@dataclass(frozen=True)
class HostFiles:
    """One host's access folder."""

    host: HostSpec
    directory: Path
    router_config: Path

    def client_config(self, account: str) -> Path:
        """The client configuration of one of this host's nodes (or ``recorder``)."""
        return account_file(self.directory, account)


@dataclass(frozen=True)
class HostAccess:
    """A run's access files across hosts."""

    directory: Path
    hosts: dict[str, HostFiles]
    tlm_config: Path


def write_host_access(directory: Path, mission: str, n_observers: int,
                      host_map: HostMap, portable: bool = False,
                      processes: Sequence[Sequence[str]] = ()) -> HostAccess:
    """Fresh accounts, certificates and router configurations for every host of ``host_map``
    (see the module docstring); the map is assumed checked against the run.  ``portable``: the
    routers name their files as ``access/<file>`` (the folder copied to its host as
    ``access/``, the router started beside it), else by their paths here.  ``processes``:
    the node names each process of the run hosts (their bundles,
    ``deploy.access.bundle_keys``)."""
    directory.mkdir(parents=True, exist_ok=True)
    directory.chmod(0o700)
    authority = write_authority(directory)
    hub = host_map.hub
    spokes = [h for h in host_map.hosts if h.name != hub.name]
    names = [n for h in host_map.hosts for n in h.nodes] + [TLM_ACCOUNT]
    names += [router_name(h) for h in spokes]
    accounts = {n: Account(n, secrets.token_urlsafe(18)) for n in names}
    relays = {router_name(h): h.nodes for h in spokes}
    hosts = {h.name: _write_host(directory / h.name, mission, n_observers, host_map, h,
                                 authority, accounts,
                                 relays if h.name == hub.name else {}, portable, processes)
             for h in host_map.hosts}
    tlm = directory / f"{TLM_ACCOUNT}.json5"
    write_private(tlm, json.dumps(client_config(
        f"tls/{hub.address}:{host_map.port}", accounts[TLM_ACCOUNT], authority.pem), indent=2))
    return HostAccess(directory, hosts, tlm)


def _write_host(folder: Path, mission: str, n_observers: int, host_map: HostMap,
                host: HostSpec, authority: Authority, accounts: dict[str, Account],
                relays: dict[str, list[str]], portable: bool,
                processes: Sequence[Sequence[str]]) -> HostFiles:
    folder.mkdir(exist_ok=True)
    folder.chmod(0o700)
    (folder / "authority.pem").write_bytes(authority.pem.read_bytes())
    written = write_certificate(authority, folder, "router", router_name(host),
                                (str(host.address),))
    here = Path("access") if portable else folder
    tls = TlsFiles(here / written.certificate.name, here / written.private_key.name,
                   here / "authority.pem")
    # the read-only account on the hub alone: watchers connect there
    local = [*host.nodes, *([TLM_ACCOUNT] if host.name == host_map.hub.name else []), *relays]
    dictionary = folder / "users.txt"
    write_private(dictionary, "".join(f"{a}:{accounts[a].password}\n" for a in local))
    endpoint = f"tcp/127.0.0.1:{host_map.port}"
    for node in host.nodes:  # the recorder's account is named as its node
        write_private(folder / f"{node}.json5",
                       json.dumps(client_config(endpoint, accounts[node], None), indent=2))
    hub = host_map.hub
    uplink = None if host.name == hub.name else accounts[router_name(host)]
    acl = access_control(mission, n_observers, relays=relays,
                         hub_common_name=None if uplink is None else router_name(hub),
                         processes=processes)
    config = host_router_config(host_map, host, here / dictionary.name, tls, acl, uplink)
    router = folder / "router.json5"
    write_private(router, json.dumps(config, indent=2))
    return HostFiles(host, folder, router)


def host_router_config(host_map: HostMap, host: HostSpec, dictionary: Path, tls: TlsFiles,
                       acl: dict[str, Any], uplink: Account | None) -> dict[str, Any]:
    """A host's router: its nodes on loopback, the other hosts over TLS; with ``uplink`` (every
    host but the hub) linked to the hub over TLS with that account, trying again every
    ``RECONNECT_MS`` while the link is down."""
    port = host_map.port
    usrpwd: dict[str, Any] = {"dictionary_file": str(dictionary)}
    connect: dict[str, Any] = {"endpoints": []}
    if uplink is not None:
        usrpwd.update(user=uplink.user, password=uplink.password)
        connect = {"endpoints": [f"tls/{host_map.hub.address}:{port}"],
                   "retry": {"period_init_ms": RECONNECT_MS, "period_max_ms": RECONNECT_MS}}
    return {"mode": "router",
            "listen": {"endpoints": [f"tcp/127.0.0.1:{port}", f"tls/{host.address}:{port}"]},
            "connect": connect, "scouting": NO_SCOUTING,
            "transport": {"auth": {"usrpwd": usrpwd},
                          "link": {"tls": {"listen_certificate": str(tls.certificate),
                                           "listen_private_key": str(tls.private_key),
                                           "root_ca_certificate": str(tls.authority)}}},
            "access_control": acl}
