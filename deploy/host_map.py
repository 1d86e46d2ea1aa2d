"""A host map (``deploy/hosts/<name>.toml``, docs/hosts.md): the hosts a run spans, which
nodes each runs, and how each host's link to the others behaves.

Every host runs a Zenoh router of its own; the ground host's (the host of the ``ground`` node)
is the hub the others link to over TLS, and every node is a client of its own host's router
(``deploy/access.py``).  A host's ``[hosts.link]`` acts on what the host *sends* (as netem on its
interface would): a packet from host A to host B is delayed by A's ``delay_ms`` (± its
``jitter_ms``) and lost with A's ``loss_pct``; so "5 ms one-way between hosts" is every host at
``delay_ms = 5``.  ``[[events]]`` change a host's link for a time, in sim seconds: cut it (both
ways), or raise its delay or loss.

Without ``--hosts`` a run is on one host, every node on this machine with the run's one router
(``deploy/access.py``), and no link: the default.  A map is checked when loaded
(:func:`load_host_map`): an unknown node, a node on two hosts, a host with no address, a
negative delay, overlapping events on one host... are refused naming the key, one line each,
hosts by their name and events counted from 1 (``events[#1]``); :func:`HostMap.check_run` then
checks it against the run: its spacecraft, and no event at or after the run's end.
"""

from __future__ import annotations

import ipaddress
import re
import tomllib
from pathlib import Path
from typing import Annotated

from pydantic import Field, ValidationError, field_validator, model_validator

from interfaces.contracts import topics
from interfaces.contracts.errors import describe, did_you_mean
from interfaces.contracts.scenario.base import Section

RECORDER_NODE = "recorder"
SERVICES = (topics.SIM, topics.GROUND, RECORDER_NODE)
"""The nodes every map places once, besides the spacecraft (``sc<N>``)."""
_SPACECRAFT = re.compile(r"^sc[1-9][0-9]*$")
HostName = Annotated[str, Field(pattern=r"^[a-z][a-z0-9]{0,7}$",
                                description="letters and digits, at most 8 (it names the "
                                            "host's network namespace and interface)")]


class HostMapError(ValueError):
    """A host map that cannot be used; the message names the file and the key."""


class LinkSpec(Section):
    """How a host's link treats what the host sends (netem-like)."""

    delay_ms: float = Field(default=0.0, ge=0.0, le=10_000.0, description="one-way delay, ms")
    jitter_ms: float = Field(default=0.0, ge=0.0, le=10_000.0,
                             description="uniform ± spread of the delay, ms (order kept)")
    loss_pct: float = Field(default=0.0, ge=0.0, le=100.0,
                            description="packets dropped at random, percent")


class HostSpec(Section):
    """One host: its name, address on the hosts' network, nodes and link."""

    name: HostName
    address: ipaddress.IPv4Address
    nodes: list[str] = Field(min_length=1)
    link: LinkSpec = LinkSpec()

    @field_validator("nodes")
    @classmethod
    def _known_nodes(cls, nodes: list[str]) -> list[str]:
        for node in nodes:
            if node not in SERVICES and not _SPACECRAFT.match(node):
                raise ValueError(f"unknown node {node!r}{did_you_mean(node, SERVICES)} (a "
                                 f"host runs {', '.join(SERVICES)} or spacecraft sc<N>)")
        if len(set(nodes)) != len(nodes):
            raise ValueError(f"a node listed twice: {nodes}")
        return nodes


class LinkEvent(Section):
    """A change of ``host``'s link from sim time ``at_s`` for ``duration_s``: ``cut`` (nothing
    passes either way), or its ``delay_ms`` / ``loss_pct`` raised to the values given."""

    host: str
    at_s: float = Field(ge=0.0, description="sim time the change starts, s")
    duration_s: float = Field(gt=0.0, description="sim time it lasts, s")
    cut: bool = False
    delay_ms: float | None = Field(default=None, ge=0.0, le=10_000.0)
    loss_pct: float | None = Field(default=None, ge=0.0, le=100.0)

    @model_validator(mode="after")
    def _does_something(self) -> LinkEvent:
        if not self.cut and self.delay_ms is None and self.loss_pct is None:
            raise ValueError("an event cuts the link (cut = true) or sets delay_ms or loss_pct")
        return self

    def during(self, normal: LinkSpec) -> LinkSpec:
        """The link while the event lasts (a cut is said by :attr:`cut`, not here)."""
        return normal.model_copy(update={
            k: v for k, v in (("delay_ms", self.delay_ms), ("loss_pct", self.loss_pct))
            if v is not None})


class HostMap(Section):
    """The hosts of a run; see the module docstring."""

    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$")
    network: ipaddress.IPv4Network = ipaddress.IPv4Network("10.77.0.0/24")
    port: int = Field(default=7447, ge=1024, le=65535, description="every router's TCP port")
    hosts: list[HostSpec] = Field(min_length=1)
    events: list[LinkEvent] = []

    @model_validator(mode="after")
    def _consistent(self) -> HostMap:
        _unique("hosts: names", [h.name for h in self.hosts])
        _unique("hosts: addresses", [str(h.address) for h in self.hosts])
        where: dict[str, str] = {}
        for h in self.hosts:
            if h.address not in self.network or h.address in (self.network.network_address,
                                                              self.network.broadcast_address):
                raise ValueError(f"hosts[{h.name}].address: {h.address} is not a host address "
                                 f"of network {self.network}")
            for node in h.nodes:
                if node in where:
                    raise ValueError(f"hosts[{h.name}].nodes: {node} is on two hosts, "
                                     f"{where[node]} and {h.name}")
                where[node] = h.name
        missing = [s for s in SERVICES if s not in where]
        if missing:
            raise ValueError(f"hosts: no host runs {', '.join(missing)}")
        names = [h.name for h in self.hosts]
        for i, e in enumerate(self.events):
            if e.host not in names:
                raise ValueError(f"events[#{i + 1}].host: no host {e.host!r} in this map"
                                 f"{did_you_mean(e.host, names)} (hosts: {', '.join(names)})")
            for j, o in enumerate(self.events[:i]):
                if o.host == e.host and (e.at_s < o.at_s + o.duration_s
                                         and o.at_s < e.at_s + e.duration_s):
                    raise ValueError(f"events[#{i + 1}]: overlaps events[#{j + 1}] on host "
                                     f"{e.host} (one change of a link at a time)")
        return self

    def host_of(self, node: str) -> HostSpec:
        """The host that runs ``node``; ValueError when none does."""
        for h in self.hosts:
            if node in h.nodes:
                return h
        raise ValueError(f"host map {self.name}: no host runs {node}")

    @property
    def hub(self) -> HostSpec:
        """The ground host, whose router the others link to."""
        return self.host_of(topics.GROUND)

    def check_run(self, participants: list[str], duration_s: float | None = None) -> None:
        """Refuse a map whose spacecraft are not exactly the run's (``participants``: the
        lockstep nodes, ``sc1``... and ``ground``), or, given the run's ``duration_s`` (s), an
        event starting at or after its end (it would never happen)."""
        for i, e in enumerate(self.events):
            if duration_s is not None and e.at_s >= duration_s:
                raise HostMapError(f"host map {self.name}: events[#{i + 1}] (host {e.host}) "
                                   f"at_s = {e.at_s:g}: not before the end of the run "
                                   f"(duration_s = {duration_s:g})")
        placed = {n for h in self.hosts for n in h.nodes if _SPACECRAFT.match(n)}
        run = {p for p in participants if _SPACECRAFT.match(p)}
        if placed - run:
            raise HostMapError(f"host map {self.name}: {', '.join(sorted(placed - run))} not in "
                               f"this run (its spacecraft: {', '.join(sorted(run))})")
        if run - placed:
            raise HostMapError(f"host map {self.name}: no host runs "
                               f"{', '.join(sorted(run - placed))}")

    def with_links(self, delay_ms: float | None, loss_pct: float | None) -> HostMap:
        """This map with every host's link delay and/or loss set (None: as declared)."""
        update = {k: v for k, v in (("delay_ms", delay_ms), ("loss_pct", loss_pct))
                  if v is not None}
        try:
            hosts = [h.model_copy(update={"link": LinkSpec.model_validate(
                {**h.link.model_dump(), **update})}) for h in self.hosts]
        except ValidationError as e:
            raise HostMapError(describe(e, "--link-delay-ms/--link-loss-pct", LinkSpec)) from None
        return self.model_copy(update={"hosts": hosts})

    def with_events(self, events: list[LinkEvent]) -> HostMap:
        """This map with ``events`` added (checked as the map's own; HostMapError naming the
        first that is not, as ``--link-event``)."""
        return parse_host_map({**self.model_dump(), "events": [
            *(e.model_dump() for e in self.events), *(e.model_dump() for e in events)]},
            f"--link-event (host map {self.name})")


def _unique(what: str, values: list[str]) -> None:
    twice = sorted({v for v in values if values.count(v) > 1})
    if twice:
        raise ValueError(f"{what} must differ: {', '.join(twice)} twice")


def load_host_map(path: Path) -> HostMap:
    """Read and check a host map; :class:`HostMapError` naming the file and each bad key."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise HostMapError(f"cannot read host map {path}: {e.strerror}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise HostMapError(f"{path}: not valid TOML: {e}") from None
    return parse_host_map(data, str(path))


def parse_host_map(data: dict[str, object], source: str) -> HostMap:
    """``data`` (a parsed TOML table) as a HostMap; :class:`HostMapError` naming each bad key,
    one line each (hosts by their name)."""
    try:
        return HostMap.model_validate(data)
    except ValidationError as e:
        raise HostMapError(describe(e, source, HostMap, data)) from None


def parse_link_event(text: str) -> LinkEvent:
    """A ``--link-event`` option: ``HOST:cut:AT_S:DURATION_S``, ``HOST:delay=MS:AT_S:DURATION_S``
    or ``HOST:loss=PCT:AT_S:DURATION_S``; ValueError saying the form."""
    parts = text.split(":")
    form = "HOST:cut|delay=MS|loss=PCT:AT_S:DURATION_S"
    if len(parts) != 4:
        raise ValueError(f"--link-event {text!r}: expected {form}")
    host, what, at_s, duration_s = parts
    kind, _, value = what.partition("=")
    fields: dict[str, object] = {"host": host, "at_s": at_s, "duration_s": duration_s}
    if kind == "cut" and not value:
        fields["cut"] = True
    elif kind in ("delay", "loss") and value:
        fields["delay_ms" if kind == "delay" else "loss_pct"] = value
    else:
        raise ValueError(f"--link-event {text!r}: expected {form}")
    try:
        return LinkEvent.model_validate(fields)
    except ValidationError as e:
        raise ValueError(describe(e, f"--link-event {text!r}", LinkEvent)) from None
