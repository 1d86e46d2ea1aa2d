"""The rehearsal's network: one Ethernet switch whose ports are the hosts' links, each a TAP
device moved into its host's namespace, and which treats every frame a host sends as that
host's link says (docs/hosts.md):

* delayed by ``delay_ms`` ± ``jitter_ms`` (uniform; a link keeps its frames in order),
* lost with probability ``loss_pct``,
* nothing passing either way while the link is cut.

This is what ``tc qdisc ... netem`` does on a host's interface; it is done here, in user
space, because the kernels this runs on may lack netem (this one has neither netem nor fq), and
it acts on real frames: every host's kernel runs its own TCP over them (retransmissions,
timeouts, Zenoh's lease), as on separate machines.  A switch with MAC learning: a frame for
an unknown address (ARP) floods.

    python -m deploy.rehearsal.wire --plan PLAN.json [--stats STATS.json]

PLAN: ``{"seed": N, "mtu": M, "ports": [{"name", "tap", "netns" (null: this namespace),
"address": "A.B.C.D/P", "link": {delay_ms, jitter_ms, loss_pct}}]}``.  The wire makes the TAPs,
moves and addresses them, prints ``ready``, then reads link changes on stdin, one JSON object a
line (``{"port": NAME, "delay_ms"..., "up": false}``), answering each ``ok`` (or ``error: ...``).
It stops at the end of stdin (its launcher gone) or on SIGTERM; its TAPs go with it.  The
frames each port passed, dropped by loss and dropped by a cut are written to STATS.
"""

from __future__ import annotations

import argparse
import fcntl
import heapq
import json
import os
import selectors
import signal
import struct
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from deploy.rehearsal.netns import ip

_TUNSETIFF = 0x400454CA
_IFF_TAP = 0x0002
_IFF_NO_PI = 0x1000
MAX_FRAME = 65_536
BROADCAST = 0x01
"""The group bit of a frame's first destination byte: broadcast or multicast."""


@dataclass
class Link:
    """What a port does to the frames its host sends."""

    delay_s: float = 0.0
    jitter_s: float = 0.0
    loss: float = 0.0
    """probability, 0-1"""
    up: bool = True

    @classmethod
    def from_spec(cls, spec: dict[str, Any]) -> Link:
        return cls(spec.get("delay_ms", 0.0) / 1e3, spec.get("jitter_ms", 0.0) / 1e3,
                   spec.get("loss_pct", 0.0) / 100.0)

    def changed(self, change: dict[str, Any]) -> Link:
        """This link with a control line's changes."""
        return Link(change["delay_ms"] / 1e3 if "delay_ms" in change else self.delay_s,
                    change["jitter_ms"] / 1e3 if "jitter_ms" in change else self.jitter_s,
                    change["loss_pct"] / 100.0 if "loss_pct" in change else self.loss,
                    bool(change.get("up", self.up)))


@dataclass
class Port:
    name: str
    fd: int
    link: Link
    last_out: float = 0.0
    """departure time of its last frame (a link keeps its frames in order)"""
    counts: dict[str, int] = field(default_factory=lambda: {
        "sent": 0, "delivered": 0, "lost": 0, "cut": 0, "unwritable": 0})


@dataclass
class Switch:
    """The switch's logic, apart from its file descriptors' loop (tests drive it directly)."""

    rng: np.random.Generator
    ports: dict[str, Port] = field(default_factory=dict)
    _macs: dict[bytes, str] = field(default_factory=dict)
    _queue: list[tuple[float, int, str, bytes]] = field(default_factory=list)
    _seq: int = 0

    def receive(self, name: str, frame: bytes, now: float) -> None:
        """A frame host ``name`` sent at ``now`` (s): dropped, or queued for its time."""
        port = self.ports[name]
        port.counts["sent"] += 1
        if not port.link.up:
            port.counts["cut"] += 1
            return
        link = port.link
        if link.loss > 0.0 and self.rng.random() < link.loss:
            port.counts["lost"] += 1
            return
        jitter = self.rng.uniform(-link.jitter_s, link.jitter_s) if link.jitter_s > 0 else 0.0
        due = max(now + max(0.0, link.delay_s + jitter), port.last_out)
        port.last_out = due
        if len(frame) >= 12:
            self._macs[frame[6:12]] = name
        self._seq += 1
        heapq.heappush(self._queue, (due, self._seq, name, frame))

    def next_due(self) -> float | None:
        """When the next queued frame leaves (s), or None."""
        return self._queue[0][0] if self._queue else None

    def deliver(self, now: float) -> list[tuple[str, bytes]]:
        """The frames due by ``now``, each with the port it goes out of (a cut port's are
        dropped and counted)."""
        out: list[tuple[str, bytes]] = []
        while self._queue and self._queue[0][0] <= now:
            _, _, source, frame = heapq.heappop(self._queue)
            for name in self._destinations(source, frame):
                port = self.ports[name]
                if port.link.up:
                    out.append((name, frame))
                else:
                    self.ports[source].counts["cut"] += 1
        return out

    def _destinations(self, source: str, frame: bytes) -> list[str]:
        known = self._macs.get(frame[0:6]) if frame and not frame[0] & BROADCAST else None
        if known is not None:
            return [] if known == source else [known]
        return [n for n in self.ports if n != source]

    def counts(self) -> dict[str, dict[str, int]]:
        return {n: dict(p.counts) for n, p in self.ports.items()}


def open_tap(name: str) -> int:
    """A new TAP device ``name`` (gone when the descriptor closes), non-blocking."""
    fd = os.open("/dev/net/tun", os.O_RDWR | os.O_NONBLOCK)
    try:
        fcntl.ioctl(fd, _TUNSETIFF, struct.pack("16sH", name.encode(), _IFF_TAP | _IFF_NO_PI))
    except OSError:
        os.close(fd)
        raise
    return fd


def plug(port: dict[str, Any], fd_name: str, mtu: int) -> None:
    """Move TAP ``fd_name`` into the port's namespace (if any), address it and bring it up."""
    netns = port.get("netns")
    where: list[str] = ["-n", netns] if netns else []
    if netns:
        ip("link", "set", fd_name, "netns", netns)
    ip(*where, "addr", "add", port["address"], "dev", fd_name)
    ip(*where, "link", "set", fd_name, "mtu", str(mtu), "up")


def serve(switch: Switch, control: int, stop: list[bool]) -> None:
    """The switch's loop: frames in, frames out at their time, link changes from ``control``
    (a line each; its end stops the loop, as does ``stop[0]``)."""
    sel = selectors.DefaultSelector()
    by_fd = {p.fd: p.name for p in switch.ports.values()}
    for fd in by_fd:
        sel.register(fd, selectors.EVENT_READ)
    sel.register(control, selectors.EVENT_READ)
    pending = b""
    while not stop[0]:
        due = switch.next_due()
        timeout = 0.5 if due is None else max(0.0, due - time.monotonic())
        for key, _ in sel.select(timeout):
            if key.fd == control:
                chunk = os.read(control, 4096)
                if not chunk:
                    return
                pending += chunk
                *lines, pending = pending.split(b"\n")
                for line in lines:
                    _answer(_change(switch, line))
                continue
            if not _read_frames(switch, by_fd[key.fd], key.fd):  # its host went away
                sel.unregister(key.fd)
                switch.ports[by_fd[key.fd]].link.up = False
        for name, frame in switch.deliver(time.monotonic()):
            _write_frame(switch.ports[name], frame)


def _read_frames(switch: Switch, name: str, fd: int) -> bool:
    """Take every frame waiting on port ``name``; False when its TAP is gone (its namespace
    removed: ``deploy/rehearsal/cluster.py`` tears a host down)."""
    while True:
        try:
            frame = os.read(fd, MAX_FRAME)
        except BlockingIOError:
            return True
        except OSError:
            return False
        switch.receive(name, frame, time.monotonic())


def _write_frame(port: Port, frame: bytes) -> None:
    try:
        os.write(port.fd, frame)
        port.counts["delivered"] += 1
    except OSError:  # its queue full, or it went down
        port.counts["unwritable"] += 1


def _change(switch: Switch, line: bytes) -> str:
    """Apply one control line; ``ok`` or ``error: ...``."""
    try:
        change = json.loads(line)
        port = switch.ports[change["port"]]
        port.link = port.link.changed(change)
    except (ValueError, KeyError, TypeError) as e:
        return f"error: {type(e).__name__}: {e}"
    return "ok"


def _answer(text: str) -> None:
    sys.stdout.write(text + "\n")
    sys.stdout.flush()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m deploy.rehearsal.wire", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--plan", type=Path, required=True)
    p.add_argument("--stats", type=Path)
    args = p.parse_args(argv)
    plan = json.loads(args.plan.read_text(encoding="utf-8"))
    stop = [False]
    signal.signal(signal.SIGTERM, lambda *_: stop.__setitem__(0, True))
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the launcher stops it: stdin or SIGTERM
    switch = Switch(np.random.default_rng(plan["seed"]))
    try:
        for port in plan["ports"]:
            fd = open_tap(port["tap"])
            switch.ports[port["name"]] = Port(port["name"], fd, Link.from_spec(port["link"]))
            plug(port, port["tap"], plan["mtu"])
    except Exception as e:  # noqa: BLE001 - said to the launcher, which stops
        _answer(f"error: {e}")
        return 2
    _answer("ready")
    try:
        serve(switch, sys.stdin.fileno(), stop)
    finally:
        if args.stats is not None:
            args.stats.write_text(json.dumps(switch.counts(), indent=2), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
