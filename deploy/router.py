"""The run's Zenoh router as a process of its own:

    python -m deploy.router --config <out>/access/router.json5 [--audit FILE]

Every node of a secured run is a client of this router, which authenticates it and enforces the
run's access-control rules (``deploy.access``).  The router refuses a session without valid
credentials and drops, silently for the sender, any message outside the sender's rights; it
keeps running until SIGINT/SIGTERM.

``--audit FILE`` makes the refusals visible: the router's access-control decisions are traced,
every refusal (failed login or denied message) is logged here (the first few of each kind, then
one in a thousand) and counted, and the counts are written to FILE (JSON) as they change and at
exit.  A declared publisher's first message on a key is decided with the key's other
permissions (as when a subscriber declares it) and is not counted.  Tracing costs the router
a few log lines per message routed, so it is off by default.
"""

from __future__ import annotations

import argparse
import errno
import json
import logging
import os
import re
import signal
import socket
import sys
import threading
from collections import Counter
from pathlib import Path

from interfaces.runtime.signals import signal_setter

AUDIT_TARGETS = ("warn,zenoh::net::routing::interceptor::access_control=trace,"
                 "zenoh_transport::unicast::establishment::accept=debug")
"""Zenoh log directives of an audited router: access-control decisions, authentication."""
_THREAD = re.compile(r"ThreadId\((?P<thread>\d+)\)")
_CACHING = re.compile(r"caching permissions for `(?P<key>[^`]*)`")
_CHECK = re.compile(r"(?P<id>[0-9a-f]{8,}) on \S*Username\((?P<user>[^)]*)\)\S* is "
                    r"(?P<verdict>authorized|unauthorized) to (?P<what>[A-Za-z/ ]+?) "
                    r"\((?P<flow>ingress|egress)\) on (?P<key>\S+)")
_CACHED_DENIAL = re.compile(r"Using cached result: (?P<id>[0-9a-f]+) is unauthorized to "
                            r"(?P<what>[A-Za-z/ ]+?) \(ingress\) on (?P<key>\S+)")
_LOGIN = re.compile(r"UsrPwd extension.*(?P<why>Invalid password|Invalid user|"
                    r"Expected extension)")

log = logging.getLogger("insp.router")


ADDRESS_TAKEN = ("address already in use", "addrinuse", "address in use")
"""What the router's log says when its endpoint's address is another process's."""


def address_taken(log_text: str) -> bool:
    """Whether the router's log (``log_text``) says its endpoint's address is taken (another
    run on it, say), rather than another failure (a malformed endpoint, a bad configuration)."""
    return any(t in log_text.lower() for t in ADDRESS_TAKEN)


def endpoint_taken(endpoint: str) -> str | None:
    """Before a router is started on a tcp or tls ``endpoint`` of this host: the error naming
    it, and a free port to give instead, if another process listens there (None: free, or not
    a tcp/tls endpoint, or not an address of this host: the router itself then says)."""
    proto, _, rest = endpoint.partition("/")
    host, _, port = rest.split("?", 1)[0].rpartition(":")
    if proto not in ("tcp", "tls") or not port.isdigit():
        return None
    family = socket.AF_INET6 if ":" in host.strip("[]") else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the router binds
        try:
            probe.bind((host.strip("[]"), int(port)))
        except OSError as e:
            if e.errno != errno.EADDRINUSE:
                return None
            probe.bind((host.strip("[]"), 0))
            free = probe.getsockname()[1]
            return (f"--endpoint {endpoint}: the address is in use (another run?): give "
                    f"another, e.g. --endpoint {proto}/{host}:{free}")
    return None


class Audit:
    """Counts of the router's refusals, by kind (``<flow> <what> by <user>`` or
    ``login: <why>``), written to ``path``."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.counts: Counter[str] = Counter()
        self._trace = _Trace()
        self._lock = threading.Lock()
        self.write()

    def line(self, text: str) -> None:
        """One line of the router's trace: count and log it if it is a refusal."""
        kind = self._trace.refusal(text)
        if kind is None:
            return
        with self._lock:
            self.counts[kind] += 1
            n = self.counts[kind]
        if n <= 5 or n % 1000 == 0:
            log.warning("refused (#%d of this kind): %s", n, kind)
        if n <= 5 or n % 100 == 0:
            self.write()

    def write(self) -> None:
        with self._lock:
            data = {"refused": dict(self.counts), "total": sum(self.counts.values())}
        tmp = self.path.with_suffix(".tmp")
        tmp.write_text(json.dumps(data, indent=2), encoding="utf-8")
        tmp.replace(self.path)


class _Trace:
    """Reads the router's access-control trace.  When Zenoh first meets a key expression for a
    session (a subscriber's declaration, a publisher's first message) it caches the session's
    permissions for it, one check per message kind, after a "caching permissions" line; those
    checks are not messages and are skipped.  Every other denial at ingress is a message refused:
    checked in full (a key without a cached entry) or from the cache."""

    def __init__(self) -> None:
        self.users: dict[str, str] = {}
        self.caching: dict[str, str] = {}

    def refusal(self, text: str) -> str | None:
        """The kind of refusal ``text`` reports, or None."""
        m = _THREAD.search(text)
        thread = m["thread"] if m is not None else ""
        m = _CACHING.search(text)
        if m is not None:
            self.caching[thread] = m["key"]
            return None
        m = _CHECK.search(text)
        if m is not None:
            self.users[m["id"]] = m["user"]
            if (m["verdict"] == "authorized" or m["flow"] == "egress"
                    or self.caching.get(thread) == m["key"]):
                return None
            return f"{m['what']} on {_space(m['key'])} by {m['user']}"
        self.caching.pop(thread, None)
        m = _CACHED_DENIAL.search(text)
        if m is not None:
            return f"{m['what']} on {_space(m['key'])} by {self.users.get(m['id'], 'unknown')}"
        m = _LOGIN.search(text)
        if m is not None:
            return f"login: {m['why'].lower()}"
        return None


def _space(key: str) -> str:
    """The key space of a key (``insp/<m>/sc/<N>``, ``insp/<m>/sim``...), for counting."""
    parts = key.split("/")
    return "/".join(parts[:4] if len(parts) > 3 and parts[2] == "sc" else parts[:3])


def _trace_to(audit: Audit) -> None:
    """Route this process's stdout and stderr (where Zenoh writes its log) through ``audit``;
    Python's own log goes on to the original stderr."""
    original = os.dup(2)
    read, write = os.pipe()
    os.dup2(write, 1)
    os.dup2(write, 2)
    os.close(write)
    logging.getLogger().handlers[0].setStream(os.fdopen(original, "w", buffering=1))

    def pump() -> None:
        with os.fdopen(read, errors="replace") as lines:
            for text in lines:
                audit.line(text)

    threading.Thread(target=pump, name="audit", daemon=True).start()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m deploy.router", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--config", required=True, type=Path, help="router JSON5 (deploy.access)")
    p.add_argument("--audit", type=Path, help="count refusals into this JSON file")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, stream=sys.stderr,
                        format="%(asctime)s  router %(levelname)s %(message)s",
                        datefmt="%H:%M:%S")
    import zenoh

    audit = Audit(args.audit) if args.audit else None
    if audit is not None:
        os.environ["RUST_LOG"] = AUDIT_TARGETS
        os.environ["NO_COLOR"] = "1"
        _trace_to(audit)
    zenoh.init_log_from_env_or("warn")
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal_setter(stop))
    try:
        session = zenoh.open(zenoh.Config.from_file(str(args.config)))
    except Exception as e:  # noqa: BLE001 - zenoh raises ZError
        log.error("cannot start the router: %s", e)
        return 2
    log.info("router up (%s)", args.config)
    try:
        while not stop.wait(0.5):
            pass
    finally:
        session.close()
        if audit is not None:
            audit.write()
            log.info("refusals: %s", dict(audit.counts) or "none")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
