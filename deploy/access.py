"""Who may do what on a run's Zenoh network: accounts and access-control rules, generated from
the scenario for each run and written under ``<out>/access/`` (readable by the owner only).

The launcher's session is the run's Zenoh *router*; every process is a *client* of it with an
account of its own (user/password authentication; the router's dictionary is
``access/users.txt``), so every message passes the router, and the router's access-control rules
(default: deny) decide:

============  ===========================================  ======================================
account       may publish (put, liveliness token, schemas)  may subscribe
============  ===========================================  ======================================
``sim``       ``insp/<m>/sim/**`` (ticks, truth, sensors,   the mission
              its status)
``sc<N>``     ``insp/<m>/sc/<N>/**``                       the mission
``ground``    ``insp/<m>/ground/**`` (assignments, fault   the mission
              reports, FDIR series)
``recorder``  its liveliness token only                    the mission
``tlm``       nothing (read-only telemetry account for     the mission
              outside viewers: ``python -m ground.tools.tlm``,
              any Zenoh client)
============  ===========================================  ======================================

Each node may besides put its process's bundles of hardware traffic
(``interfaces.contracts.bundle``): ``insp/<m>/bundle/<node>``, and the first node of a process
hosting several that process's, ``insp/<m>/bundle/sc1-sc2-sc3``: the key names the nodes whose
rows a receiver takes from it, so no account can carry a node its process does not host.

A client without an account cannot open a session at all; a put outside the publisher's own key
space is dropped by the router (silently, for the publisher).  The key space a message came on
therefore names its sender, which the Bus checks against the body
(``interfaces.runtime.admission``).

Each account's client configuration is ``access/<account>.json5`` (endpoint, user, password
and, with TLS, the certificate authority inline: the one file is all a node on another host
needs): the ``--zenoh-config`` of every node process and of ``ground.tools.tlm``.  With a ``tls/``
endpoint the router serves the certificate of ``access/tls/`` (``deploy.certificates``) and
clients verify it against the run's own authority.
"""

from __future__ import annotations

import base64
import json
import os
import secrets
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from interfaces.contracts import topics
from interfaces.contracts.bundle import bundle_key

TLM_ACCOUNT = "tlm"
"""The read-only telemetry account."""
RECORDER_ACCOUNT = "recorder"


@dataclass(frozen=True)
class Account:
    user: str
    password: str


@dataclass(frozen=True)
class TlsFiles:
    """The router's certificate and key, and the authority that signed it (PEM files)."""

    certificate: Path
    private_key: Path
    authority: Path


@dataclass(frozen=True)
class RunAccess:
    """A run's written access files."""

    directory: Path
    router_config: Path
    endpoint: str

    def client_config(self, account: str) -> Path:
        """The client configuration file of ``account`` (a node name, ``recorder`` or ``tlm``)."""
        return account_file(self.directory, account)


def account_file(directory: Path, account: str) -> Path:
    """``account``'s client configuration in ``directory`` (a run's access folder, or a host's);
    FileNotFoundError naming both when there is none."""
    path = directory / f"{account}.json5"
    if not path.is_file():
        raise FileNotFoundError(f"no account {account!r} in {directory}")
    return path


def publishers(n_observers: int) -> list[str]:
    """The nodes that publish: the sim, every spacecraft, the ground."""
    return [topics.SIM, *(topics.sc_node(i) for i in range(1, n_observers + 1)), topics.GROUND]


PUBLISH = ["put", "delete", "liveliness_token", "declare_queryable", "reply"]
"""What a node may do in its own key space."""


def grants(mission: str, account: str, processes: Sequence[Sequence[str]] = ()
           ) -> list[tuple[list[str], list[str]]]:
    """What ``account`` (a node, or the recorder) may publish, as (messages, key expressions):
    a node everything in its key space and the bundles of its process
    (:func:`bundle_keys`), the recorder its liveliness token alone."""
    if account == RECORDER_ACCOUNT:
        return [(["liveliness_token"], [topics.recorder_token(mission)])]
    return [(PUBLISH, [f"{topics.node_prefix(mission, account)}/**"]),
            (["put"], bundle_keys(mission, account, processes))]


def bundle_keys(mission: str, node: str, processes: Sequence[Sequence[str]]) -> list[str]:
    """The bundle keys node ``node`` may publish (``interfaces.contracts.bundle``): its own,
    as a node alone in its process, and, as the first node of one of the run's ``processes``
    (the node names each hosts) hosting several, that process's: its session sends the
    process's bundles.  No account may name a node its process does not host."""
    return [bundle_key(mission, [node])] + [bundle_key(mission, p) for p in processes
                                           if len(p) > 1 and p[0] == node]


EVERY_MESSAGE = ["put", "delete", "reply", "liveliness_token", "declare_subscriber",
                 "declare_liveliness_subscriber", "declare_queryable", "query",
                 "liveliness_query"]
"""Every message kind the access rules name."""


def access_control(mission: str, n_observers: int,
                   relays: dict[str, list[str]] | None = None,
                   hub_common_name: str | None = None,
                   processes: Sequence[Sequence[str]] = ()) -> dict[str, Any]:
    """The router's ``access_control`` block: default deny; every account may subscribe to the
    mission, query schemas and watch liveliness; each publisher may publish, declare its token
    and serve its schemas in its own key space only; the recorder may declare its token.

    Across hosts (docs/hosts.md): the hub's ``relays`` are the other hosts' routers' accounts,
    each with the nodes of its host: a relay may publish what those nodes may, and is sent
    everything in the mission.  A router that links to the hub trusts, in and out, the link
    whose certificate (verified against the run's authority) bears the common name
    ``hub_common_name``: the hub enforced the rules already.  ``processes``: the node names
    each of the run's processes hosts (the bundle keys, :func:`bundle_keys`)."""
    mission_keys = [topics.mission_wildcard(mission)]
    relays = relays or {}
    everyone = [*publishers(n_observers), RECORDER_ACCOUNT, TLM_ACCOUNT, *relays]
    rules: list[dict[str, Any]] = [
        _rule("receive", ["put", "delete", "reply", "liveliness_token"], "egress", mission_keys),
        # a publisher must learn of subscribers, or it drops its data; a subscriber's key
        # expression may be wider than the mission (ground.tools.tlm's default insp/**)
        _rule("see-subscribers", ["declare_subscriber"], "egress", [f"{topics.ROOT}/**"]),
        _rule("subscribe", ["declare_subscriber", "declare_liveliness_subscriber", "query",
                            "liveliness_query"], "ingress", [f"{topics.ROOT}/**"]),
    ]
    subjects: list[dict[str, Any]] = [{"id": f"user-{u}", "usernames": [u]} for u in everyone]
    policies = [{"rules": ["receive", "see-subscribers", "subscribe"],
                 "subjects": [f"user-{u}" for u in everyone]}]
    own = {a: grants(mission, a, processes)
           for a in [*publishers(n_observers), RECORDER_ACCOUNT]}
    own.update({relay: [g for n in nodes for g in grants(mission, n, processes)]
                for relay, nodes in relays.items()})
    for user, granted in own.items():
        ids = []
        for i, (messages, keys) in enumerate(granted):
            rules += [_rule(f"publish-{user}-{i}", messages, "ingress", keys),
                      _rule(f"serve-{user}-{i}", ["query"], "egress", keys)]
            ids += [f"publish-{user}-{i}", f"serve-{user}-{i}"]
        policies.append({"rules": ids, "subjects": [f"user-{user}"]})
    if relays:
        rules.append(_rule("relay-out", EVERY_MESSAGE, "egress", mission_keys))
        policies.append({"rules": ["relay-out"], "subjects": [f"user-{r}" for r in relays]})
    if hub_common_name is not None:
        rules += [_rule("hub-in", EVERY_MESSAGE, "ingress", [f"{topics.ROOT}/**"]),
                  _rule("hub-out", EVERY_MESSAGE, "egress", [f"{topics.ROOT}/**"])]
        subjects.append({"id": "hub", "cert_common_names": [hub_common_name]})
        policies.append({"rules": ["hub-in", "hub-out"], "subjects": ["hub"]})
    return {"enabled": True, "default_permission": "deny", "rules": rules,
            "subjects": subjects, "policies": policies}


def _rule(rule_id: str, messages: list[str], flow: str, keys: list[str]) -> dict[str, Any]:
    return {"id": rule_id, "messages": messages, "flows": [flow], "permission": "allow",
            "key_exprs": keys}


def router_config(endpoint: str, dictionary: Path, acl: dict[str, Any],
                  tls: TlsFiles | None) -> dict[str, Any]:
    """The launcher's router: listens on ``endpoint`` only, no scouting, every client
    authenticated against ``dictionary``, ``acl`` enforced."""
    transport: dict[str, Any] = {"auth": {"usrpwd": {"dictionary_file": str(dictionary)}}}
    if tls is not None:
        transport["link"] = {"tls": {"listen_certificate": str(tls.certificate),
                                     "listen_private_key": str(tls.private_key)}}
    return {"mode": "router", "listen": {"endpoints": [endpoint]}, "connect": {"endpoints": []},
            "scouting": NO_SCOUTING, "transport": transport, "access_control": acl}


def client_config(endpoint: str, account: Account, authority: Path | None) -> dict[str, Any]:
    """A client of the router at ``endpoint`` with ``account``'s credentials (verifying the
    router's certificate against ``authority``, a PEM file copied in, on a ``tls/`` endpoint)."""
    transport: dict[str, Any] = {"auth": {"usrpwd": {"user": account.user,
                                                     "password": account.password}}}
    if authority is not None:  # inline, so that the one file is all another host needs
        pem = base64.b64encode(authority.read_bytes()).decode()
        transport["link"] = {"tls": {"root_ca_certificate_base64": pem}}
    return {"mode": "client", "connect": {"endpoints": [endpoint]}, "scouting": NO_SCOUTING,
            "transport": transport}


NO_SCOUTING = {"multicast": {"enabled": False}, "gossip": {"enabled": False}}


def write_run_access(directory: Path, mission: str, n_observers: int, endpoint: str,
                     tls: TlsFiles | None = None, clients_connect: str | None = None,
                     processes: Sequence[Sequence[str]] = ()) -> RunAccess:
    """Create fresh accounts (random passwords) and write the router's dictionary and
    configuration (listening on ``endpoint``) and every account's client configuration
    (connecting to ``clients_connect``, by default ``endpoint``) into ``directory`` (mode 0700,
    files 0600).  ``tls`` is required for a ``tls/`` endpoint.  ``processes``: the node names
    each process of the run hosts (its bundles, :func:`bundle_keys`)."""
    if endpoint.startswith("tls/") and tls is None:
        raise ValueError(f"{endpoint} needs the router's certificate (TlsFiles)")
    directory.mkdir(parents=True, exist_ok=True)
    directory.chmod(0o700)
    users = [*publishers(n_observers), RECORDER_ACCOUNT, TLM_ACCOUNT]
    accounts = [Account(u, secrets.token_urlsafe(18)) for u in users]
    dictionary = directory / "users.txt"
    write_private(dictionary, "".join(f"{a.user}:{a.password}\n" for a in accounts))
    authority = tls.authority if tls is not None else None
    for a in accounts:
        write_private(directory / f"{a.user}.json5",
                       json.dumps(client_config(clients_connect or endpoint, a, authority),
                                  indent=2))
    router = directory / "router.json5"
    write_private(router, json.dumps(router_config(
        endpoint, dictionary, access_control(mission, n_observers, processes=processes), tls),
        indent=2))
    return RunAccess(directory, router, endpoint)


def write_private(path: Path, text: str) -> None:
    """Write ``text`` to ``path``, readable and writable by the owner only."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(text)
    path.chmod(0o600)
