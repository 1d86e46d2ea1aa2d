"""A host map's network on this machine (``--rehearse``, docs/hosts.md): a namespace per host,
each host's link a port of the wire (``deploy/rehearsal/wire.py``), and one more port here, in
the launcher's own namespace, through which it watches the run (no delay, no loss).

Torn down on leaving, also after an error or a signal: the wire stopped (its links go with it)
and every namespace removed.  The processes started in the namespaces must be stopped first
(the launcher's supervisor does it); a launcher killed outright leaves its namespaces behind,
and the next rehearsal removes them (``netns.sweep``).
"""

from __future__ import annotations

import json
import logging
import os
import select
import subprocess
import sys
import time
from collections.abc import Sequence
from ipaddress import IPv4Address, IPv4Network
from pathlib import Path
from typing import IO, Protocol

from deploy.host_map import LinkSpec
from deploy.processes import die_with_parent
from deploy.rehearsal import netns
from deploy.rehearsal.netns import RehearsalError

MTU = 9000
"""The hosts' links' MTU (jumbo frames, as on a lab network: fewer frames for the wire)."""
READY_S = 20.0
"""How long the wire has to make and plug its links, wall s."""
LAUNCHER_PORT = "launcher"
log = logging.getLogger("insp.rehearsal")


class NetHost(Protocol):
    """A host of a rehearsed network: a host map's (``HostSpec``), or a cluster's."""

    @property
    def name(self) -> str: ...
    @property
    def address(self) -> IPv4Address: ...
    @property
    def link(self) -> LinkSpec: ...


class RehearsedNetwork:
    """The namespaces and wire of ``hosts`` on ``network`` for launcher ``pid`` (its logs in
    ``logs``); the wire's random draws (losses, jitter) seeded by ``seed``."""

    def __init__(self, hosts: Sequence[NetHost], network: IPv4Network, logs: Path, seed: int,
                 pid: int | None = None) -> None:
        self.hosts, self.network, self.logs, self.seed = list(hosts), network, logs, seed
        self.pid = os.getpid() if pid is None else pid
        self._wire: subprocess.Popen[bytes] | None = None
        self._wire_log: IO[bytes] | None = None
        self._mute = False

    @property
    def launcher_address(self) -> str:
        """This namespace's address on the hosts' network: the network's last host address."""
        return str(self.network.broadcast_address - 1)

    def netns(self, host: str) -> str:
        """The namespace of ``host``."""
        return netns.namespace(self.pid, host)

    def __enter__(self) -> RehearsedNetwork:
        netns.require_privilege()
        for gone in netns.sweep():
            log.warning("removed namespace %s, left by a launcher no longer running", gone)
        taken = netns.addresses_in(self.network)
        if taken:
            raise RehearsalError(f"network {self.network} is in use here ({', '.join(taken)}): "
                                 "another rehearsal of it is running, or this machine's own; "
                                 "give the map another network")
        if any(str(h.address) == self.launcher_address for h in self.hosts):
            raise RehearsalError(f"{self.launcher_address} is the launcher's address in a "
                                 "rehearsal; give the host another")
        try:
            for h in self.hosts:
                netns.add(self.netns(h.name))
            self._start_wire()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _start_wire(self) -> None:
        plan = self.logs / "wire-plan.json"
        self.logs.mkdir(parents=True, exist_ok=True)
        plan.write_text(json.dumps(self._plan(), indent=2), encoding="utf-8")
        self._wire_log = (self.logs / "wire.log").open("wb")
        self._wire = subprocess.Popen(
            [sys.executable, "-m", "deploy.rehearsal.wire", "--plan", str(plan),
             "--stats", str(self.logs / "wire.json")],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._wire_log,
            cwd=Path(__file__).resolve().parents[2], start_new_session=True,
            preexec_fn=die_with_parent)
        answer = self._read_answer(READY_S)
        if answer != "ready":
            raise RehearsalError(f"the hosts' network could not be made: {answer}")
        log.info("hosts' network up: %s", ", ".join(
            f"{h.name} {h.address} ({self.netns(h.name)})" for h in self.hosts))

    def _plan(self) -> dict[str, object]:
        prefix = self.network.prefixlen
        tag = f"i{self.pid % 100000}"
        ports = [{"name": h.name, "tap": f"{tag}.{h.name}", "netns": self.netns(h.name),
                  "address": f"{h.address}/{prefix}", "link": h.link.model_dump()}
                 for h in self.hosts]
        ports.append({"name": LAUNCHER_PORT, "tap": f"{tag}.{LAUNCHER_PORT}"[:15], "netns": None,
                      "address": f"{self.launcher_address}/{prefix}", "link": {}})
        return {"seed": self.seed, "mtu": MTU, "ports": ports}

    def set_link(self, host: str, link: LinkSpec, up: bool = True) -> None:
        """Give ``host``'s link ``link`` (and cut it unless ``up``)."""
        if self._wire is None or self._wire.stdin is None:
            raise RehearsalError("the hosts' network is not up")
        line = json.dumps({"port": host, **link.model_dump(), "up": up}) + "\n"
        try:
            self._wire.stdin.write(line.encode())
            self._wire.stdin.flush()
        except OSError as e:  # the wire is gone
            raise RehearsalError(f"link of {host} not changed: the wire is gone ({e})") from None
        answer = self._read_answer(5.0)
        if answer != "ok":
            raise RehearsalError(f"link of {host} not changed: {answer}")

    def _read_answer(self, timeout_s: float) -> str:
        """The wire's answer line; after none in time, every later change is refused (a late
        answer would be taken for the next one's)."""
        assert self._wire is not None and self._wire.stdout is not None
        if self._mute:
            return "the wire stopped answering earlier"
        ready, _, _ = select.select([self._wire.stdout], [], [], timeout_s)
        line = self._wire.stdout.readline().decode().strip() if ready else ""
        if line:
            return line
        self._mute = True
        return (f"no answer from the wire within {timeout_s:g} s "
                f"({'running' if self._wire.poll() is None else 'exited'}; see "
                f"{self.logs / 'wire.log'})")

    def close(self) -> None:
        """Stop the wire and remove every namespace this launcher made."""
        if self._wire is not None:
            if self._wire.stdin is not None:
                self._wire.stdin.close()  # its end of input: it stops
            try:
                self._wire.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self._wire.kill()
                self._wire.wait()
            self._wire = None
        if self._wire_log is not None:
            self._wire_log.close()
            self._wire_log = None
        for name in netns.ours(self.pid):
            netns.remove(name)
        deadline = time.monotonic() + 5.0
        while netns.ours(self.pid) and time.monotonic() < deadline:
            time.sleep(0.1)
